// SPDX-License-Identifier: MIT
// isokit.tracker: the 2014 iso-surface tracker on a mesh given as NumPy arrays, tracking an isokit
// field or any Python callable f(points) -> (values, gradients).
#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include "common.h"
#include "isokit/implicit/field.h"
#include "isokit/track/tracker.h"

namespace isokit::python {

using namespace isokit::track;

const implicit::Field& field_evaluator(const py::object& field);  // fields.cpp
bool is_isokit_field(const py::object& field);                    // fields.cpp

namespace {

/// Time and calls spent in a Python field during one call (reported in the statistics).
struct PythonFieldCost {
  long calls{0};
  long points{0};
  double seconds{0};
};

/// A FieldFunction over `field`: an isokit field is evaluated in C++ (in parallel); a Python
/// callable is called with the GIL, once per batch (the tracker runs with grain 0 then, so a batch
/// is all the points of one evaluation), and its results are checked.
FieldFunction field_function(const py::object& field, Released& released, PythonFieldCost& cost) {
  if (is_isokit_field(field)) {
    const implicit::Field* f = &field_evaluator(field);
    return [f](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients, std::uint8_t*) {
      std::vector<implicit::FieldSample> out(n);
      f->eval_batch(p, n, out.data(), 0);
      for (std::size_t i = 0; i < n; ++i) {
        values[i] = out[i].value;
        gradients[i] = out[i].gradient;
      }
    };
  }
  require(PyCallable_Check(field.ptr()) != 0, "argument 'field'",
          "must be an isokit.fields.Field or a callable f(points) -> (values, gradients)",
          "pass e.g. lambda p: (values, gradients) with p of shape (N, 3)");
  const py::object* fn = &field;
  return [fn, &released, &cost](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients,
                                std::uint8_t* contact) {
    released.call([&] {
      const auto t0 = std::chrono::steady_clock::now();
      py::array_t<float> points({static_cast<py::ssize_t>(n), py::ssize_t{3}});
      if (n > 0) std::memcpy(points.mutable_data(), p, n * 3 * sizeof(float));
      const py::object result = (*fn)(points);
      require(py::isinstance<py::tuple>(result) && (py::len(result) == 2 || py::len(result) == 3),
              "the Python field", "must return (values, gradients) or (values, gradients, contact)",
              "return a tuple of arrays of shapes (N,), (N, 3)");
      const py::tuple t = result.cast<py::tuple>();
      const auto v = real_array<float>(t[0], "values returned by the field", {static_cast<py::ssize_t>(n)});
      const auto g =
          real_array<float>(t[1], "gradients returned by the field", {static_cast<py::ssize_t>(n), 3});
      std::memcpy(values, v.data(), n * sizeof(float));
      std::memcpy(static_cast<void*>(gradients), g.data(), n * 3 * sizeof(float));
      if (py::len(t) == 3) {
        const auto c =
            real_array<std::uint8_t>(t[2], "contact returned by the field", {static_cast<py::ssize_t>(n)});
        std::memcpy(contact, c.data(), n);
      }
      ++cost.calls;
      cost.points += static_cast<long>(n);
      cost.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
  };
}

py::array_t<float> to_array(const Positions& p) {
  py::array_t<float> out({static_cast<py::ssize_t>(p.rows()), py::ssize_t{3}});
  if (p.size() > 0)
    std::memcpy(out.mutable_data(), p.data(), static_cast<std::size_t>(p.size()) * sizeof(float));
  return out;
}

template <class T>
py::array_t<T> to_array(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(T));
  return out;
}

py::dict stats_dict(const TrackStats& s, const PythonFieldCost& cost) {
  py::dict d;
  d["iterations"] = s.iterations;
  d["converged"] = s.converged;
  d["vertex_updates"] = s.vertex_updates;
  d["field_evaluations"] = s.field_evaluations;
  d["solver_iterations"] = s.solver_iterations;
  d["max_move"] = s.max_move;
  d["max_residual"] = s.max_residual;
  d["mean_residual"] = s.mean_residual;
  d["contact_vertices"] = s.contact_vertices;
  d["smoothed_vertices"] = s.smoothed_vertices;
  d["lost_vertices"] = s.lost_vertices;
  d["free_vertices"] = s.free_vertices;
  d["inverted_triangles"] = s.inverted_triangles;
  d["seconds"] = s.seconds;
  d["python_field_calls"] = cost.calls;
  d["python_field_points"] = cost.points;
  d["python_field_seconds"] = cost.seconds;
  return d;
}

/// TrackerOptions from keyword arguments (the names of tracker_options.h).
TrackerOptions options_from(const py::dict& kw) {
  TrackerOptions o;
  for (const auto& [key_obj, value] : kw) {
    const std::string key = py::str(key_obj);
    auto num = [&](auto& field) {
      try {
        field = value.cast<std::decay_t<decltype(field)>>();
      } catch (const py::cast_error&) {
        throw InputError("argument '" + key + "': wrong type (" + std::string(py::str(py::repr(value))) +
                         ")");
      }
    };
    if (key == "sigma")
      num(o.sigma);
    else if (key == "max_iterations")
      num(o.max_iterations);
    else if (key == "tolerance")
      num(o.tolerance);
    else if (key == "initial_newton_steps")
      num(o.initial_newton_steps);
    else if (key == "contact_angle_deg")
      num(o.contact_angle_deg);
    else if (key == "angle_contacts")
      num(o.angle_contacts);
    else if (key == "fold_contacts")
      num(o.fold_contacts);
    else if (key == "max_step")
      num(o.max_step);
    else if (key == "smoothing_steps")
      num(o.smoothing.smoothing_steps);
    else if (key == "beta_diffusion_steps")
      num(o.smoothing.beta_diffusion_steps);
    else if (key == "lazy_evaluation")
      num(o.lazy_evaluation);
    else if (key == "active_set")
      num(o.active_set);
    else
      throw InputError("argument '" + key +
                       "': not a tracker option (sigma, max_iterations, tolerance, initial_newton_steps, "
                       "contact_angle_deg, angle_contacts, fold_contacts, max_step, smoothing_steps, "
                       "beta_diffusion_steps, lazy_evaluation, active_set)");
  }
  return o;
}

class PyTracker {
 public:
  PyTracker(const py::object& rest, const py::object& triangles, const py::object& iso, const py::kwargs& kw)
      : options_(options_from(kw)) {
    rest_ = positions_of(rest, "rest");
    triangles_ = triangles_of(triangles, "triangles");
    const auto v = real_array<float>(iso, "iso", {rest_.rows()});
    iso_.assign(v.data(), v.data() + v.size());
  }

  py::tuple track(const py::object& field, const py::object& positions, const py::object& rotations,
                  const py::object& mask, const py::object& anchors, const py::object& stiffness) {
    Positions p = positions_of(positions, "positions", rest_.rows());
    std::vector<Mat3f> rot;
    if (!rotations.is_none()) {
      const auto r = real_array<float>(rotations, "rotations", {rest_.rows(), 3, 3});
      rot.resize(static_cast<std::size_t>(rest_.rows()));
      for (std::size_t i = 0; i < rot.size(); ++i)
        std::copy(r.data() + 9 * i, r.data() + 9 * i + 9, rot[i].m);
    }
    const bool python_field = !is_isokit_field(field);
    TrackerOptions o = options_;
    if (python_field) o.grain = 0;  // one call with every point per evaluation, on one thread
    if (!tracker_ || python_field != python_field_) {
      tracker_ = std::make_unique<IsoSurfaceTracker>(rest_, triangles_, iso_, o);
      python_field_ = python_field;
    }
    // The mask of this call (none: every vertex relaxes), not one left by an earlier call.
    if (!mask.is_none()) {
      const auto m = real_array<float>(mask, "mask", {rest_.rows()});
      tracker_->set_relaxation_mask(std::vector<float>(m.data(), m.data() + m.size()));
    } else {
      tracker_->set_relaxation_mask(std::vector<float>(static_cast<std::size_t>(rest_.rows()), 1.0f));
    }
    // The anchors of this call: stiffness (V,) in [0, 1] toward anchors (V, 3) (default: the
    // initial positions); none: no anchor.
    std::vector<float> k(static_cast<std::size_t>(rest_.rows()), 0.0f);
    if (!stiffness.is_none()) {
      const auto s = real_array<float>(stiffness, "stiffness", {rest_.rows()});
      k.assign(s.data(), s.data() + s.size());
    } else {
      require(anchors.is_none(), "argument 'anchors'", "given without 'stiffness'",
              "pass stiffness (V,) in [0, 1]: how strongly each vertex is pulled to its anchor");
    }
    tracker_->set_anchor_stiffness(std::move(k));
    const Positions a = anchors.is_none() ? p : positions_of(anchors, "anchors", rest_.rows());
    Released released;
    PythonFieldCost cost;
    const FieldFunction f = field_function(field, released, cost);
    TrackStats stats;
    released.run([&] { stats = tracker_->track(f, rot, p, a); });
    return py::make_tuple(to_array(p), stats_dict(stats, cost));
  }

  py::dict flags() const {
    require(tracker_ != nullptr, "Tracker.flags", "no call yet", "call track first");
    const VertexFlags& f = tracker_->flags();
    py::dict d;
    d["contact"] = to_array(f.contact);
    d["lost"] = to_array(f.lost);
    d["beta"] = to_array(f.beta);
    d["free"] = to_array(f.free);
    return d;
  }

 private:
  TrackerOptions options_;
  Positions rest_;
  Triangles triangles_;
  std::vector<float> iso_;
  std::unique_ptr<IsoSurfaceTracker> tracker_;
  bool python_field_{false};
};

}  // namespace

void bind_tracker(py::module_& m) {
  m.def(
      "sample_iso_values",
      [](const py::object& field, const py::object& positions) {
        const Positions p = positions_of(positions, "positions");
        Released released;
        PythonFieldCost cost;
        const FieldFunction f = field_function(field, released, cost);
        std::vector<float> iso;
        released.run([&] { iso = sample_iso_values(f, p); });
        return to_array(iso);
      },
      py::arg("field"), py::arg("positions"),
      "The field's values at the rest positions: the iso-values the tracker keeps each vertex on.");
  py::class_<PyTracker>(m, "Tracker",
                        "The 2014 iso-surface tracker (ARAP relaxation in the tangent planes, Newton "
                        "projections, contacts): moves a mesh onto iso-values of a moving field.")
      .def(py::init<const py::object&, const py::object&, const py::object&, const py::kwargs&>(),
           py::arg("rest"), py::arg("triangles"), py::arg("iso"),
           "rest (V, 3), triangles (F, 3) int, iso (V,) target values (sample_iso_values); options as "
           "keywords (sigma, max_iterations, tolerance, ... of TrackerOptions).")
      .def("track", &PyTracker::track, py::arg("field"), py::arg("positions"),
           py::arg("rotations") = py::none(), py::arg("mask") = py::none(), py::arg("anchors") = py::none(),
           py::arg("stiffness") = py::none(),
           "Tracks `field` (an isokit.fields.Field, or a callable f(points (N, 3) float32) -> (values "
           "(N,), gradients (N, 3)[, contact (N,)]) called from one thread with every point of an "
           "evaluation) from the initial `positions` (V, 3); rotations (V, 3, 3) are the ARAP targets "
           "(default identity), mask (V,) the relaxation mask (a scale of the tangential step); "
           "stiffness (V,) in [0, 1] pulls each vertex toward its anchor (V, 3; default: the initial "
           "positions), 1 pins it there (2014 Fig. 11 as a term of the solve). Returns (positions, "
           "statistics dict).")
      .def_property_readonly("flags", &PyTracker::flags,
                             "Per-vertex flags of the last call (contact, lost, beta, free).");
}

}  // namespace isokit::python
