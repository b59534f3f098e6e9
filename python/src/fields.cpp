// SPDX-License-Identifier: MIT
// isokit.fields: analytic primitives, HRBFs fitted to points and normals, grids, and composition
// trees of them with isokit's operators, evaluated (value and gradient) on (N, 3) arrays.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/hrbf.h"
#include "isokit/implicit/primitives.h"
#include "isokit/implicit/program_field.h"
#include "isokit/implicit/tree.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"

namespace isokit::python {

using namespace isokit::implicit;

namespace {

/// A field as Python sees it: a composition tree (a leaf for a single field). Single leaves are
/// evaluated directly; inner nodes through a compiled program (made once, on first use).
class PyField {
 public:
  explicit PyField(CompositionTree tree) : tree_(std::move(tree)) {}

  const CompositionTree& tree() const { return tree_; }
  const Field& evaluator() const {
    if (tree_.is_leaf() && is_identity(tree_.transform())) return *tree_.field();
    if (!program_) program_ = std::make_shared<ProgramField>(tree_);
    return *program_;
  }

 private:
  static bool is_identity(const Rigid3f& xf) {
    const Rigid3f id{};
    return std::equal(std::begin(xf.R.m), std::end(xf.R.m), std::begin(id.R.m)) && xf.t.x == 0 &&
           xf.t.y == 0 && xf.t.z == 0;
  }
  CompositionTree tree_;
  mutable std::shared_ptr<const ProgramField> program_;
};

Vec3f vec3(const py::object& obj, const char* name) {
  const auto a = real_array<float>(obj, name, {3});
  return {a.data()[0], a.data()[1], a.data()[2]};
}

float positive(double x, const char* name) {
  require(std::isfinite(x) && x > 0, std::string("argument '") + name + "'",
          "must be finite and > 0 (got " + format_number(x) + ")", "give a positive length");
  return static_cast<float>(x);
}

/// values (N,), gradients (N, 3) of `field` at `points` (N, 3); the GIL is released meanwhile.
/// The field writes straight into one (N, 4) buffer (FieldSample's layout: value, gradient); the
/// two results are views of it, so nothing is copied on the way out.
py::tuple evaluate(const Field& field, const py::object& points_obj) {
  static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");
  static_assert(sizeof(FieldSample) == 4 * sizeof(float), "FieldSample must be four packed floats");
  const auto points = real_array<float>(points_obj, "points", {-1, 3});
  const auto n = static_cast<std::size_t>(points.shape(0));
  py::array_t<float> samples({static_cast<py::ssize_t>(n), py::ssize_t{4}});
  const float* p = points.data();
  float* out = samples.mutable_data();
  {
    py::gil_scoped_release release;
    field.eval_batch(reinterpret_cast<const Vec3f*>(p), n, reinterpret_cast<FieldSample*>(out));
  }
  return py::make_tuple(
      samples[py::make_tuple(py::slice(0, static_cast<py::ssize_t>(n), 1), 0)],
      samples[py::make_tuple(py::slice(0, static_cast<py::ssize_t>(n), 1), py::slice(1, 4, 1))]);
}

/// Seconds of the C++ call `evaluate` wraps (eval_batch into a FieldSample buffer), best of
/// `repeats`: the reference of the Python overhead benchmark (bench/python/bench_python.py).
double cpp_eval_seconds(const Field& field, const py::object& points_obj, int repeats) {
  const auto points = real_array<float>(points_obj, "points", {-1, 3});
  const auto n = static_cast<std::size_t>(points.shape(0));
  const auto* p = reinterpret_cast<const Vec3f*>(points.data());
  double best = 1e300;
  py::gil_scoped_release release;
  std::vector<FieldSample> out(n);
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    field.eval_batch(p, n, out.data());
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

/// An HRBF through `points` with `normals` (outward), remapped by t_r with width `r` (default:
/// half the points' bounding-box diagonal), its support box grown until the field is 0 on it.
PyField fit_hrbf(const py::object& points_obj, const py::object& normals_obj, std::optional<double> r_opt) {
  const auto p = real_array<double>(points_obj, "points", {-1, 3});
  const auto nrm = real_array<double>(normals_obj, "normals", {p.shape(0), 3});
  require(p.shape(0) >= 4, "argument 'points'",
          "needs at least 4 points (got " + std::to_string(p.shape(0)) + ")",
          "give points on the surface with their normals");
  std::vector<HrbfSample> samples(static_cast<std::size_t>(p.shape(0)));
  Box3d box;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].position = {p.data()[3 * i], p.data()[3 * i + 1], p.data()[3 * i + 2]};
    samples[i].normal = {nrm.data()[3 * i], nrm.data()[3 * i + 1], nrm.data()[3 * i + 2]};
    box.extend(samples[i].position);
  }
  const Vec3d diag = box.hi - box.lo;
  const double r = r_opt ? *r_opt : 0.5 * std::sqrt(dot(diag, diag));
  positive(r, "r");
  std::shared_ptr<const Hrbf> hrbf;
  {
    py::gil_scoped_release release;
    hrbf = std::make_shared<const Hrbf>(samples, HrbfOptions{}, "points");
  }
  std::string last;
  for (double grow : {1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0}) {
    const double g = grow * r;
    const Box3f b{{float(box.lo.x - g), float(box.lo.y - g), float(box.lo.z - g)},
                  {float(box.hi.x + g), float(box.hi.y + g), float(box.hi.z + g)}};
    try {
      return PyField(CompositionTree::leaf(std::make_shared<const HrbfField>(hrbf, r, b)));
    } catch (const InputError& e) {
      last = e.what();
    }
  }
  throw InputError("fit_hrbf: no support box up to 8 r contains the field (" + last +
                   "); check that the normals point outward, or give a larger r");
}

PyField grid_of(const PyField& f, int resolution) {
  GridFieldOptions o;
  o.resolution = resolution;
  std::shared_ptr<const GridField> grid;
  {
    py::gil_scoped_release release;
    grid = std::make_shared<const GridField>(f.evaluator(), Box3f{}, o);
  }
  return PyField(CompositionTree::leaf(grid));
}

/// Node data of GridField (value, gradient per node, x fastest) from NumPy nodes[i, j, k] (i along
/// x): values (n, n, n), gradients by central differences (one-sided on the faces), or (n, n, n, 4).
PyField grid_from_nodes(const py::object& nodes_obj, const py::object& lo_obj, const py::object& hi_obj) {
  const auto nodes = real_array<float>(nodes_obj, "nodes");
  const bool with_gradients = nodes.ndim() == 4;
  require((nodes.ndim() == 3 || (with_gradients && nodes.shape(3) == 4)) &&
              nodes.shape(0) == nodes.shape(1) && nodes.shape(1) == nodes.shape(2) && nodes.shape(0) >= 2,
          "argument 'nodes'", "must be (n, n, n) values or (n, n, n, 4) values and gradients, n >= 2",
          "sample the field on a cube lattice");
  const auto n = static_cast<std::size_t>(nodes.shape(0));
  const Vec3f lo = vec3(lo_obj, "lo");
  const Vec3f hi = vec3(hi_obj, "hi");
  const float* src = nodes.data();
  const std::size_t per = with_gradients ? 4 : 1;
  auto value = [&](std::size_t i, std::size_t j, std::size_t k) { return src[((i * n + j) * n + k) * per]; };
  std::vector<float> data(4 * n * n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k) {
        float* out = &data[4 * ((k * n + j) * n + i)];
        if (with_gradients) {
          std::copy(src + 4 * ((i * n + j) * n + k), src + 4 * ((i * n + j) * n + k) + 4, out);
          continue;
        }
        out[0] = value(i, j, k);
        const std::size_t at[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          std::size_t m[3] = {i, j, k};
          std::size_t q[3] = {i, j, k};
          m[a] = at[a] > 0 ? at[a] - 1 : 0;
          q[a] = at[a] + 1 < n ? at[a] + 1 : n - 1;
          const float h = (hi[a] - lo[a]) / static_cast<float>(n - 1);
          out[1 + a] =
              (value(q[0], q[1], q[2]) - value(m[0], m[1], m[2])) / (static_cast<float>(q[a] - m[a]) * h);
        }
      }
  return PyField(CompositionTree::leaf(
      std::make_shared<const GridField>(static_cast<int>(n), Box3f{lo, hi}, std::move(data))));
}

Rigid3f rigid(const py::object& rotation, const py::object& translation) {
  const auto r = real_array<float>(rotation, "rotation", {3, 3});
  Rigid3f xf;
  std::copy(r.data(), r.data() + 9, xf.R.m);
  xf.t = vec3(translation, "translation");
  validate_rigid(xf, "argument 'rotation'");
  return xf;
}

operators::Controller controller_of(const py::object& c, const char* fallback) {
  if (c.is_none()) return operators::Controller::preset(fallback);
  if (py::isinstance<py::str>(c)) return operators::Controller::preset(c.cast<std::string>());
  return c.cast<operators::Controller>();
}

}  // namespace

bool is_isokit_field(const py::object& field) {
  return py::isinstance<PyField>(field);
}

const Field& field_evaluator(const py::object& field) {
  return field.cast<const PyField&>().evaluator();
}

void bind_fields(py::module_& m) {
  py::class_<PyField>(m, "Field",
                      "An isokit field: values in [0, 1], 0.5 on the surface, > 0.5 inside, gradients "
                      "pointing inward, compact support.")
      .def(
          "evaluate",
          [](const PyField& f, const py::object& points) { return evaluate(f.evaluator(), points); },
          py::arg("points"), "(values (N,), gradients (N, 3)) at points (N, 3); float32.")
      .def(
          "_cpp_eval_seconds",
          [](const PyField& f, const py::object& points, int repeats) {
            return cpp_eval_seconds(f.evaluator(), points, repeats);
          },
          py::arg("points"), py::arg("repeats") = 5,
          "Benchmark reference: the C++ call alone (best of repeats).")
      .def_property_readonly("support",
                             [](const PyField& f) {
                               const Box3f b = f.evaluator().support();
                               return py::make_tuple(py::make_tuple(b.lo.x, b.lo.y, b.lo.z),
                                                     py::make_tuple(b.hi.x, b.hi.y, b.hi.z));
                             })
      .def_property_readonly("is_leaf", [](const PyField& f) { return f.tree().is_leaf(); })
      .def_property_readonly("leaf_count", [](const PyField& f) { return f.tree().leaf_count(); })
      .def(
          "transformed",
          [](const PyField& f, const py::object& rotation, const py::object& translation) {
            require(f.tree().is_leaf(), "transformed", "applies to a single field, not a composition",
                    "transform the operands before composing them");
            return PyField(CompositionTree::leaf(f.tree().field(), rigid(rotation, translation)));
          },
          py::arg("rotation"), py::arg("translation"),
          "This field moved rigidly: world = rotation @ local + translation (rotation 3 x 3 orthonormal).")
      .def(
          "to_grid", [](const PyField& f, int resolution) { return grid_of(f, resolution); },
          py::arg("resolution") = 32,
          "This field sampled on a resolution^3 grid over its support (2013 §6).");

  m.def(
      "sphere",
      [](const py::object& center, double radius, double width) {
        return PyField(CompositionTree::leaf(std::make_shared<const SphereField>(
            vec3(center, "center"), positive(radius, "radius"), static_cast<float>(width))));
      },
      py::arg("center"), py::arg("radius"), py::arg("support_width") = 0.0,
      "A sphere: its distance remapped by the 2013 t_r (support_width 0: the radius).");
  m.def(
      "capsule",
      [](const py::object& a, const py::object& b, double radius, double width) {
        return PyField(CompositionTree::leaf(std::make_shared<const CapsuleField>(
            vec3(a, "a"), vec3(b, "b"), positive(radius, "radius"), static_cast<float>(width))));
      },
      py::arg("a"), py::arg("b"), py::arg("radius"), py::arg("support_width") = 0.0,
      "A capsule around the segment a-b (support_width 0: the radius).");
  m.def("fit_hrbf", &fit_hrbf, py::arg("points"), py::arg("normals"), py::arg("r") = py::none(),
        "An HRBF (2013 §4) through points (N, 3) with outward normals (N, 3), remapped by t_r of width "
        "r (default: half the points' bounding-box diagonal).");
  m.def(
      "grid", &grid_from_nodes, py::arg("nodes"), py::arg("lo"), py::arg("hi"),
      "A field sampled on an (n, n, n) lattice spanning the box lo-hi: nodes[i, j, k] at lo + (i, j, k) "
      "(hi - lo) / (n - 1), values (gradients by central differences) or (n, n, n, 4) values and gradients; "
      "interpolated as isokit's grid fields (2013 §6).");
  m.def(
      "union",
      [](const PyField& a, const PyField& b) {
        return PyField(CompositionTree::node(NodeOperator::max(), a.tree(), b.tree()));
      },
      py::arg("a"), py::arg("b"), "max(f1, f2): the union.");
  m.def(
      "clean_union",
      [](const PyField& a, const PyField& b) {
        return PyField(CompositionTree::node(NodeOperator::clean_union(), a.tree(), b.tree()));
      },
      py::arg("a"), py::arg("b"), "The clean union (2013 §5).");
  m.def(
      "sum_blend",
      [](const PyField& a, const PyField& b) {
        return PyField(CompositionTree::node(NodeOperator::sum_blend(), a.tree(), b.tree()));
      },
      py::arg("a"), py::arg("b"), "The sum blend.");
  m.def(
      "gradient_blend",
      [](const PyField& a, const PyField& b, const py::object& controller) {
        return PyField(CompositionTree::node(
            NodeOperator::gradient_blend(controller_of(controller, "blend2013")), a.tree(), b.tree()));
      },
      py::arg("a"), py::arg("b"), py::arg("controller") = py::none(),
      "The 2013 gradient-based blend; controller: a Controller or preset name (default blend2013).");
  m.def(
      "compose",
      [](const PyField& a, const PyField& b, const py::object& grid_obj, const py::object& controller,
         const std::string& name) {
        const auto g = real_array<float>(grid_obj, "grid", {-1, -1, -1});
        require(g.shape(1) == g.shape(2), "argument 'grid'", "must be (nd, nf, nf)", "pass a generated grid");
        std::vector<float> data(static_cast<std::size_t>(g.size()));
        if (!data.empty()) std::memcpy(data.data(), g.data(), data.size() * sizeof(float));
        auto grid = std::make_shared<const operators::GridOperator>(
            static_cast<int>(g.shape(0)), static_cast<int>(g.shape(1)), std::move(data));
        return PyField(CompositionTree::node(
            NodeOperator::grid_operator(grid, controller_of(controller, "contact"), name), a.tree(),
            b.tree()));
      },
      py::arg("a"), py::arg("b"), py::arg("grid"), py::arg("controller") = py::none(),
      py::arg("name") = "grid",
      "a and b composed by an operator grid (isokit.operators.generate); the controller (a Controller "
      "or preset name, default contact) picks the slice from the angle between the gradients (2014 §4).");
}

}  // namespace isokit::python
