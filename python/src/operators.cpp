// SPDX-License-Identifier: MIT
// isokit.operators: specs (as dicts or JSON files), the biharmonic generator, operator grids
// evaluated on arrays, controllers and the checks of `isokit-opdesigner inspect`.
#include <cstring>
#include <filesystem>
#include <string>

#include "common.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/checks.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/operators/io.h"
#include "isokit/operators/spec.h"

namespace isokit::python {

using namespace isokit::operators;

namespace {

/// A spec given as a dict (the JSON schema of docs/operators.md), a JSON string path or a PathLike.
OperatorSpec to_spec(const py::object& spec) {
  if (py::isinstance<py::dict>(spec)) {
    const std::string text = py::module_::import("json").attr("dumps")(spec).cast<std::string>();
    return spec_from_json(text, "spec (dict)");
  }
  if (py::isinstance<py::str>(spec) || py::hasattr(spec, "__fspath__"))
    return load_spec(py::module_::import("os").attr("fspath")(spec).cast<std::string>());
  throw InputError("argument 'spec': expected a dict or the path of a spec JSON file, got " +
                   std::string(py::str(py::type::of(spec).attr("__name__"))));
}

py::dict to_dict(const OperatorSpec& spec) {
  return py::module_::import("json").attr("loads")(spec_to_json(spec)).cast<py::dict>();
}

py::array_t<float> grid_array(GridOperator grid) {
  auto* owned = new std::vector<float>(std::move(grid.data()));
  py::capsule free_data(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
  return py::array_t<float>({grid.nd(), grid.nf(), grid.nf()}, owned->data(), free_data);
}

GridOperator to_grid(const py::object& grid) {
  const auto a = real_array<float>(grid, "grid", {-1, -1, -1});
  require(a.shape(1) == a.shape(2), "argument 'grid'", "must be (nd, nf, nf): square slices",
          "pass a generated grid");
  const auto n = static_cast<std::size_t>(a.size());
  std::vector<float> data(n);
  if (n > 0) std::memcpy(data.data(), a.data(), n * sizeof(float));
  return GridOperator(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), std::move(data));
}

SparseBackend to_backend(const std::string& name) {
  if (name == "auto") return SparseBackend::kAuto;
  if (name == "cholmod") return SparseBackend::kCholmod;
  if (name == "sparselu") return SparseBackend::kSparseLU;
  throw InputError("argument 'backend': '" + name + "' is not one of auto, cholmod, sparselu");
}

/// g, dg/df1, dg/df2 of `grid` (evaluated in place: a float32 C-contiguous grid is not copied) at
/// equally shaped arrays (broadcast by the Python layer).
py::tuple evaluate(const py::object& grid_obj, const py::object& f1, const py::object& f2,
                   const py::object& d) {
  const auto grid = real_array<float>(grid_obj, "grid", {-1, -1, -1});
  require(grid.shape(1) == grid.shape(2) && grid.shape(0) >= 1 && grid.shape(1) >= 2, "argument 'grid'",
          "must be (nd, nf, nf) with nd >= 1 and nf >= 2", "pass a generated grid");
  const auto a = real_array<float>(f1, "f1");
  const auto b = real_array<float>(f2, "f2");
  const auto c = real_array<float>(d, "d");
  require(a.size() == b.size() && a.size() == c.size(), "arguments 'f1', 'f2', 'd'",
          "have different sizes (" + std::to_string(a.size()) + ", " + std::to_string(b.size()) + ", " +
              std::to_string(c.size()) + ")",
          "pass arrays of one shape (or use isokit.operators.Operator.evaluate, which broadcasts)");
  const auto n = static_cast<std::size_t>(a.size());
  std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
  py::array_t<float> g(shape), g1(shape), g2(shape);
  const float* pa = a.data();
  const float* pb = b.data();
  const float* pc = c.data();
  float* out[3] = {g.mutable_data(), g1.mutable_data(), g2.mutable_data()};
  {
    py::gil_scoped_release release;
    const GridOperatorView view{grid.data(), static_cast<int>(grid.shape(0)),
                                static_cast<int>(grid.shape(1))};
    for (std::size_t i = 0; i < n; ++i) {
      const OpSample s = view.eval(pa[i], pb[i], pc[i]);
      out[0][i] = s.g;
      out[1][i] = s.dg1;
      out[2][i] = s.dg2;
    }
  }
  return py::make_tuple(g, g1, g2);
}

py::dict slice_dict(const SliceReport& r) {
  py::dict d;
  d["slice"] = r.slice;
  d["d"] = r.d;
  d["boundary_error"] = r.boundary_error;
  d["axis_slope"] = r.axis_slope;
  d["iso_to_profile"] = r.iso_to_profile;
  d["profile_to_iso"] = r.profile_to_iso;
  d["contact_error"] = r.contact_error;
  d["contact_length"] = r.contact_length;
  d["monotonicity_violations"] = r.monotonicity_violations;
  d["monotonicity_max_drop"] = r.monotonicity_max_drop;
  d["cell"] = r.cell;
  return d;
}

}  // namespace

void bind_operators(py::module_& m) {
  m.def("presets", &preset_spec_names, "Names of the preset operator profiles (2014 Fig. 5 and others).");
  m.def(
      "preset_spec",
      [](const std::string& name, int resolution) { return to_dict(preset_spec(name, resolution)); },
      py::arg("name"), py::arg("resolution") = 128,
      "The spec of preset `name` as a dict (the JSON schema of docs/operators.md).");
  m.def(
      "check_spec", [](const py::object& spec) { return to_dict(to_spec(spec)); }, py::arg("spec"),
      "Reads and validates a spec (dict or JSON path); returns it as a dict. Raises InputError naming "
      "the bad item.");
  m.def(
      "generate",
      [](const py::object& spec, const std::string& backend, const py::object& progress) {
        const OperatorSpec s = to_spec(spec);
        BiharmonicOptions o;
        o.backend = to_backend(backend);
        GridOperator grid;
        Released released;
        o.progress = released.progress(progress);
        released.run([&] { grid = generate_operator(s, o); });
        return grid_array(std::move(grid));
      },
      py::arg("spec"), py::kw_only(), py::arg("backend") = "auto", py::arg("progress") = py::none(),
      "Generates the operator of `spec` (dict or JSON path) with the 2014 biharmonic generator: a "
      "float32 array (slices, resolution, resolution), grid[k, i1, i2] = g(i1 h, i2 h, d_k). "
      "`progress(done, total)` is called after each slice; Ctrl+C interrupts.");
  m.def(
      "evaluate",
      [](const py::object& grid, const py::object& f1, const py::object& f2, const py::object& d) {
        return evaluate(grid, f1, f2, d);
      },
      py::arg("grid"), py::arg("f1"), py::arg("f2"), py::arg("d"),
      "g, dg/df1, dg/df2 of an operator grid at equally shaped arrays f1, f2, d (bicubic in f, "
      "linear in d, as isokit's fields compose).");
  m.def(
      "inspect",
      [](const py::object& spec, const py::object& grid) {
        const OperatorSpec s = to_spec(spec);
        const GridOperator g = to_grid(grid);
        require(g.nd() == s.slices && g.nf() == s.resolution, "argument 'grid'",
                "shape does not match the spec (" + std::to_string(s.slices) + ", " +
                    std::to_string(s.resolution) + ", " + std::to_string(s.resolution) + ")",
                "generate the grid from this spec");
        py::list slices;
        py::object failure = py::none();
        for (int k = 0; k < g.nd(); ++k) {
          const SliceReport r = inspect_slice(s, g, k);
          slices.append(slice_dict(r));
          if (failure.is_none())
            if (const auto f = judge_slice(r)) failure = py::str(f->message());
        }
        py::dict out;
        out["slices"] = slices;
        out["failure"] = failure;
        return out;
      },
      py::arg("spec"), py::arg("grid"),
      "The checks of `isokit-opdesigner inspect`: a dict with 'slices' (one report per slice) and "
      "'failure' (the first failed check's message, or None).");
  m.def(
      "load",
      [](const py::object& path) {
        StoredOperator op = load_operator(py::module_::import("os").attr("fspath")(path).cast<std::string>());
        return py::make_tuple(to_dict(op.spec), grid_array(std::move(op.grid)));
      },
      py::arg("path"),
      "Reads an operator written by isokit (OP.npy beside OP.json): (spec dict, grid array).");
  m.def(
      "save",
      [](const py::object& path, const py::object& spec, const py::object& grid) {
        save_operator(py::module_::import("os").attr("fspath")(path).cast<std::string>(), to_spec(spec),
                      to_grid(grid));
      },
      py::arg("path"), py::arg("spec"), py::arg("grid"),
      "Writes OP.npy and OP.json (isokit's operator files).");

  py::class_<Controller>(m, "Controller", "A controller curve d(alpha) (2014 Fig. 4): joint angle -> slice.")
      .def(py::init([](const py::object& knots, const std::string& name) {
             const auto k = real_array<double>(knots, "knots", {-1, 2});
             std::vector<ControllerKnot> list;
             for (py::ssize_t i = 0; i < k.shape(0); ++i) list.push_back({k.at(i, 0), k.at(i, 1)});
             return Controller(std::move(list), name);
           }),
           py::arg("knots"), py::arg("name") = "custom",
           "From knots [[alpha, d], ...]: alpha in radians from 0 to pi, d in [0, 1].")
      .def_static("preset", &Controller::preset, py::arg("name"), "A preset: contact, bulge, blend2013, ...")
      .def_static("presets", &Controller::preset_names)
      .def_property_readonly("name", &Controller::name)
      .def_property_readonly(
          "knots",
          [](const Controller& c) {
            py::array_t<double> out({static_cast<py::ssize_t>(c.knots().size()), py::ssize_t{2}});
            auto v = out.mutable_unchecked<2>();
            for (std::size_t i = 0; i < c.knots().size(); ++i) {
              v(static_cast<py::ssize_t>(i), 0) = c.knots()[i].alpha;
              v(static_cast<py::ssize_t>(i), 1) = c.knots()[i].d;
            }
            return out;
          })
      .def(
          "__call__",
          [](const Controller& c, const py::object& alpha) {
            const auto a = real_array<double>(alpha, "alpha");
            py::array_t<double> out(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
            for (py::ssize_t i = 0; i < a.size(); ++i) out.mutable_data()[i] = c.eval(a.data()[i]);
            return out;
          },
          py::arg("alpha"), "d at the angles `alpha` (radians, clamped to [0, pi]).");
}

}  // namespace isokit::python
