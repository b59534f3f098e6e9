// SPDX-License-Identifier: MIT
// isokit.skinning: load a rig (file or procedural), fit its implicit skin, bake a clip, bends, a
// pose script or poses from NumPy with any method, read the frames and metrics as arrays and
// dicts, write the baked glTF or a point cache — the same steps as `isokit-skin bake`.
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common.h"
#include "isokit/skinning/bake_job.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/report.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/self_overlap.h"
#include "isokit/skinning/setup.h"

namespace isokit::python {

using namespace isokit::skinning;

namespace {

std::string path_of(const py::object& p) {
  return py::module_::import("os").attr("fspath")(p).cast<std::string>();
}

Progress stage_progress(Released& released, const py::object& callback) {
  const py::object* cb = &callback;
  return [&released, cb](const std::string& stage, int done, int total) {
    released.call([&] {
      if (!cb->is_none()) (*cb)(stage, done, total);
    });
  };
}

py::array_t<float> positions_array(const track::Positions& p) {
  py::array_t<float> out({static_cast<py::ssize_t>(p.rows()), py::ssize_t{3}});
  if (p.size() > 0)
    std::memcpy(out.mutable_data(), p.data(), static_cast<std::size_t>(p.size()) * sizeof(float));
  return out;
}

py::array_t<double> poses_array(const std::vector<Pose>& poses, std::size_t joints) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), static_cast<py::ssize_t>(joints),
                           py::ssize_t{4}, py::ssize_t{4}});
  double* d = out.mutable_data();
  for (const Pose& pose : poses)
    for (const Affine& a : pose)
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) *d++ = a.matrix()(r, c);
  return out;
}

std::vector<Pose> poses_from(const py::object& obj, std::size_t joints) {
  const auto a = real_array<double>(obj, "poses", {-1, static_cast<py::ssize_t>(joints), 4, 4});
  std::vector<Pose> poses(static_cast<std::size_t>(a.shape(0)), Pose(joints));
  const double* d = a.data();
  for (Pose& pose : poses)
    for (Affine& t : pose) {
      Eigen::Matrix4d m;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = *d++;
      t.matrix() = m;
      t.matrix().row(3) << 0, 0, 0, 1;
    }
  require(!poses.empty(), "argument 'poses'", "has no frame",
          "give (frames, joints, 4, 4) local joint transforms");
  return poses;
}

SkinSetup setup_from(const py::object& setup) {
  if (setup.is_none()) return SkinSetup{};
  if (py::isinstance<py::dict>(setup))
    return setup_from_json(py::module_::import("json").attr("dumps")(setup).cast<std::string>(),
                           "setup (dict)");
  return load_setup(path_of(setup));
}

/// Where a Skinner's progress goes: the Python call in progress, if any (the Skinner keeps its
/// progress function for its bakes; it must not outlive one call's `Released`).
struct ProgressSlot {
  Released* released{nullptr};
  const py::object* callback{nullptr};
};

/// Points `slot` at one call's `released` and `callback` for the lifetime of the guard.
class SlotGuard {
 public:
  SlotGuard(ProgressSlot& slot, Released& released, const py::object& callback) : slot_(slot) {
    slot_.released = &released;
    slot_.callback = &callback;
  }
  ~SlotGuard() { slot_ = ProgressSlot{}; }
  SlotGuard(const SlotGuard&) = delete;
  SlotGuard& operator=(const SlotGuard&) = delete;

 private:
  ProgressSlot& slot_;
};

Progress slot_progress(const std::shared_ptr<ProgressSlot>& slot) {
  return [slot](const std::string& stage, int done, int total) {
    if (slot->released == nullptr) return;
    slot->released->call([&] {
      if (!slot->callback->is_none()) (*slot->callback)(stage, done, total);
    });
  };
}

/// A rig and its fitted skin (a Skinner), shared by the results baked with it.
struct PySkinner {
  std::shared_ptr<Skinner> skinner;
  std::shared_ptr<ProgressSlot> slot = std::make_shared<ProgressSlot>();
  std::vector<std::string> warnings;
};

struct PyResult {
  std::shared_ptr<Skinner> skinner;
  BakeResult result;
  std::string animation;
  double fps{30};

  ReportContext context() const {
    return ReportContext{animation, fps, static_cast<int>(std::thread::hardware_concurrency()),
                         skinner->fitted().fit_seconds(), std::nullopt};
  }
};

py::dict rig_summary(const Rig& rig) {
  py::dict d;
  d["name"] = rig.name;
  d["vertices"] = rig.rest.rows();
  d["triangles"] = rig.triangles.rows();
  py::list joints, clips;
  for (const Joint& j : rig.joints) joints.append(j.name);
  for (const Clip& c : rig.clips) clips.append(py::make_tuple(c.name, c.frame_count(), c.fps));
  d["joints"] = joints;
  d["clips"] = clips;
  return d;
}

}  // namespace

/// A rig from arrays (a DCC's mesh and armature): joints parents first, their world transforms at
/// the bind pose, dense weights (V, J) normalised per vertex.
std::shared_ptr<Rig> rig_from_arrays(const py::object& vertices, const py::object& triangles,
                                     const std::vector<std::string>& joints, const std::vector<int>& parents,
                                     const py::object& bind_world, const py::object& weights,
                                     const std::string& name) {
  auto rig = std::make_shared<Rig>();
  rig->name = name;
  const auto v = real_array<float>(vertices, "vertices", {-1, 3});
  rig->rest.resize(v.shape(0), 3);
  if (v.size() > 0)
    std::memcpy(rig->rest.data(), v.data(), static_cast<std::size_t>(v.size()) * sizeof(float));
  const auto t = real_array<int>(triangles, "triangles", {-1, 3});
  rig->triangles.resize(t.shape(0), 3);
  if (t.size() > 0)
    std::memcpy(rig->triangles.data(), t.data(), static_cast<std::size_t>(t.size()) * sizeof(int));
  const auto nj = static_cast<py::ssize_t>(joints.size());
  require(
      parents.size() == joints.size(), "argument 'parents'",
      "has " + std::to_string(parents.size()) + " entries for " + std::to_string(joints.size()) + " joints",
      "give one parent index per joint (-1 for a root)");
  const auto world = real_array<double>(bind_world, "bind_world", {nj, 4, 4});
  std::vector<Affine> w(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m(r, c) = world.data()[16 * j + static_cast<std::size_t>(4 * r + c)];
    w[j].matrix() = m;
    w[j].matrix().row(3) << 0, 0, 0, 1;
  }
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const int p = parents[j];
    require(p < static_cast<int>(j), "argument 'parents'",
            "joint " + std::to_string(j) + " ('" + joints[j] + "') has parent " + std::to_string(p) +
                ", not an earlier joint",
            "order the joints parents first");
    const Affine local = p < 0 ? w[j] : Affine(w[static_cast<std::size_t>(p)].inverse(Eigen::Affine) * w[j]);
    rig->joints.emplace_back(joints[j], p, local, w[j].inverse(Eigen::Affine));
  }
  const auto wt = real_array<float>(weights, "weights", {rig->rest.rows(), nj});
  SkinWeights sw;
  sw.offsets.push_back(0);
  for (py::ssize_t i = 0; i < wt.shape(0); ++i) {
    for (py::ssize_t j = 0; j < nj; ++j) {
      const float x = wt.data()[i * nj + j];
      if (x != 0) {
        sw.joints.push_back(static_cast<int>(j));
        sw.weights.push_back(x);
      }
    }
    sw.offsets.push_back(static_cast<int>(sw.joints.size()));
  }
  normalize_weights(sw, static_cast<int>(rig->rest.rows()), 0.0f, name);
  rig->weights = std::move(sw);
  validate(*rig);
  return rig;
}

/// `self_overlap(vertices, triangles, resolution)` as a dict (self_overlap.h).
py::dict self_overlap_of(const py::object& vertices, const py::object& triangles, int resolution,
                         bool mark_triangles) {
  const track::Positions p = positions_of(vertices, "vertices");
  const track::Triangles f = triangles_of(triangles, "triangles");
  SelfOverlapOptions o;
  o.resolution = resolution;
  o.mark_triangles = mark_triangles;
  SelfOverlap r;
  {
    py::gil_scoped_release released;
    r = self_overlap(p, f, o);
  }
  py::dict out;
  out["overlap"] = r.overlap;
  out["enclosed"] = r.enclosed;
  out["cell"] = r.cell;
  out["columns"] = r.columns;
  out["open_columns"] = r.open_columns;
  py::array_t<int> marked(static_cast<py::ssize_t>(r.overlap_triangles.size()));
  if (!r.overlap_triangles.empty())
    std::memcpy(marked.mutable_data(), r.overlap_triangles.data(), r.overlap_triangles.size() * sizeof(int));
  out["triangles"] = marked;
  return out;
}

/// `folded_triangles(rig, frames, poses)`: per frame and triangle, folded (folds.h) and not folded
/// at rest, as a (F, T) bool array.
py::array_t<bool> folded_triangles_of(const Rig& rig, const py::object& frames, const py::object& poses) {
  const py::array_t<float, py::array::c_style | py::array::forcecast> a(frames);
  const std::vector<Pose> p = poses_from(poses, rig.joints.size());
  require(a.ndim() == 3 && a.shape(1) == rig.rest.rows() && a.shape(2) == 3, "folded_triangles: frames",
          "must be (frames, " + std::to_string(rig.rest.rows()) + ", 3)",
          "pass BakeResult.frames of this rig");
  require(static_cast<std::size_t>(a.shape(0)) == p.size(), "folded_triangles: poses",
          "one pose per frame is needed (" + std::to_string(a.shape(0)) + " frames, " +
              std::to_string(p.size()) + " poses)",
          "pass the poses the frames were baked at");
  const std::size_t nf = p.size(), nt = static_cast<std::size_t>(rig.triangles.rows());
  py::array_t<bool> out({static_cast<py::ssize_t>(nf), static_cast<py::ssize_t>(nt)});
  bool* dst = out.mutable_data();
  const float* src = a.data();
  {
    py::gil_scoped_release released;
    const SkinReference ref = metrics_reference(rig);
    const FoldCounter folds(rig.rest, rig.triangles, ref.weights, ref.rest_skin);
    track::Positions posed(rig.rest.rows(), 3);
    for (std::size_t f = 0; f < nf; ++f) {
      std::memcpy(posed.data(), src + f * std::size_t(rig.rest.rows()) * 3,
                  std::size_t(rig.rest.rows()) * 3 * sizeof(float));
      const std::vector<std::uint8_t> flags = folds.folded(posed, skinning_matrices(rig, p[f]));
      for (std::size_t t = 0; t < nt; ++t) dst[f * nt + t] = flags[t] && !folds.rest_folded()[t];
    }
  }
  return out;
}

void bind_skinning(py::module_& m) {
  m.attr("DEFAULT_METHOD") = std::string(to_string(kDefaultMethod));
  m.def("folded_triangles", &folded_triangles_of, py::arg("rig"), py::arg("frames"), py::arg("poses"),
        "Per frame and triangle: folded, its normal turned by more than 90 degrees from its rest normal "
        "carried by the skinning blend's rotation, and not folded at rest (the metrics' folded_new; "
        "docs/skinning-metrics.md, 'Folds'). frames (F, V, 3) and their poses (F, joints, 4, 4); "
        "returns a (F, triangles) bool array.");
  m.def("self_overlap", &self_overlap_of, py::arg("vertices"), py::arg("triangles"),
        py::arg("resolution") = 160, py::arg("mark_triangles") = false,
        "Interpenetration by volume: the volume the mesh encloses twice (winding number >= 2) and "
        "once, by columns on a grid of `resolution` cells across the largest side (open borders "
        "closed by cones; docs/skinning-metrics.md). Returns {overlap, enclosed, cell, columns, "
        "open_columns, triangles}: triangles bounding the overlap when mark_triangles.");
  py::class_<Rig, std::shared_ptr<Rig>>(m, "Rig",
                                        "A rigged character: welded rest mesh, joints, weights, clips.")
      .def_static(
          "from_arrays", &rig_from_arrays, py::arg("vertices"), py::arg("triangles"), py::arg("joints"),
          py::arg("parents"), py::arg("bind_world"), py::arg("weights"), py::arg("name") = "arrays",
          "A rig from arrays: vertices (V, 3), triangles (F, 3), joint names parents first, parent "
          "indices (-1: root), each joint's world transform at the bind pose (J, 4, 4), weights (V, J) "
          "(normalised per vertex). For meshes and armatures from other tools (a DCC, NumPy).")
      .def_property_readonly("name", [](const Rig& r) { return r.name; })
      .def_property(
          "relax_mask",
          [](const Rig& r) -> py::object {
            if (r.relax_mask.empty()) return py::none();
            py::array_t<float> a(static_cast<py::ssize_t>(r.relax_mask.size()));
            std::memcpy(a.mutable_data(), r.relax_mask.data(), r.relax_mask.size() * sizeof(float));
            return std::move(a);
          },
          [](Rig& r, const py::object& mask) {
            if (mask.is_none()) {
              r.relax_mask.clear();
              return;
            }
            const auto a = real_array<float>(mask, "relax_mask", {r.rest.rows()});
            std::vector<float> values(a.data(), a.data() + a.size());
            for (std::size_t v = 0; v < values.size(); ++v)
              require(values[v] >= 0.f && values[v] <= 1.f, "relax_mask[" + std::to_string(v) + "]",
                      "is outside [0, 1] (" + format_number(values[v]) + ")", "use 0 (rigid) .. 1 (tracked)");
            r.relax_mask = std::move(values);
          },
          "The painted relaxation mask (V,) float32 in [0, 1], or None (every vertex tracked): 0 = "
          "moved rigidly with its nearest bone, 1 = tracked, between = pulled toward the rigid position "
          "(2014 Fig. 11). Read from a glTF `_RELAX_MASK` attribute or the setup's vertex-colour set; "
          "written by save and the baked .glb.")
      .def_property_readonly(
          "rest", [](const Rig& r) { return positions_array(r.rest); },
          "Welded rest positions (V, 3) float32.")
      .def_property_readonly(
          "triangles",
          [](const Rig& r) {
            py::array_t<int> t({static_cast<py::ssize_t>(r.triangles.rows()), py::ssize_t{3}});
            if (r.triangles.size() > 0)
              std::memcpy(t.mutable_data(), r.triangles.data(),
                          static_cast<std::size_t>(r.triangles.size()) * sizeof(int));
            return t;
          })
      .def_property_readonly("joints",
                             [](const Rig& r) {
                               std::vector<std::string> names;
                               for (const Joint& j : r.joints) names.push_back(j.name);
                               return names;
                             })
      .def_property_readonly("parents",
                             [](const Rig& r) {
                               std::vector<int> p;
                               for (const Joint& j : r.joints) p.push_back(j.parent);
                               return p;
                             })
      .def_property_readonly("clips",
                             [](const Rig& r) {
                               std::vector<std::string> names;
                               for (const Clip& c : r.clips) names.push_back(c.name);
                               return names;
                             })
      .def(
          "clip_poses",
          [](const Rig& r, const std::string& name) {
            return poses_array(clip_animation(r, name), r.joints.size());
          },
          py::arg("name"),
          "The clip's local joint transforms (frames, joints, 4, 4), sampled at the rig's fps.")
      .def(
          "rest_pose",
          [](const Rig& r) {
            py::array_t<double> out(
                {static_cast<py::ssize_t>(r.joints.size()), py::ssize_t{4}, py::ssize_t{4}});
            double* d = out.mutable_data();
            for (const Affine& a : rest_pose(r))
              for (int row = 0; row < 4; ++row)
                for (int c = 0; c < 4; ++c) *d++ = a.matrix()(row, c);
            return out;
          },
          "Local joint transforms at rest (joints, 4, 4).")
      .def(
          "add_clip",
          [](Rig& r, const std::string& name, const py::object& poses, double fps) {
            require(fps > 0 && std::isfinite(fps), "argument 'fps'", "must be > 0", "give e.g. 30");
            Clip c;
            c.name = name;
            c.fps = fps;
            c.local = poses_from(poses, r.joints.size());
            r.clips.push_back(std::move(c));
            validate(r);
          },
          py::arg("name"), py::arg("poses"), py::arg("fps") = 30.0,
          "Adds a clip: local joint transforms (frames, joints, 4, 4) at fps.")
      .def(
          "save", [](const Rig& r, const py::object& path) { save_rig(r, path_of(path)); }, py::arg("path"),
          "Writes the rig as a skinned glTF (.glb or .gltf) that isokit-skin and other tools load.")
      .def("summary", &rig_summary, "name, vertices, triangles, joints, clips (name, frames, fps).")
      .def("__repr__", [](const Rig& r) {
        return "<isokit.skinning.Rig " + r.name + ": " + std::to_string(r.rest.rows()) + " vertices, " +
               std::to_string(r.joints.size()) + " joints, " + std::to_string(r.clips.size()) + " clips>";
      });

  m.def(
      "load",
      [](const py::object& spec, double fps, const py::object& progress) {
        const std::string s = py::isinstance<py::str>(spec) ? spec.cast<std::string>() : path_of(spec);
        Released released;
        const Progress p = stage_progress(released, progress);
        auto rig = std::make_shared<Rig>();
        std::vector<std::string> warnings;
        released.run([&] { *rig = open_rig(s, fps, p, &warnings); });
        for (const std::string& w : warnings) PyErr_WarnEx(PyExc_UserWarning, ("isokit: " + w).c_str(), 1);
        return rig;
      },
      py::arg("path"), py::arg("fps") = 30.0, py::arg("progress") = py::none(),
      "A rig from a file (.glb, .gltf, .fbx, .dae) or `procedural:NAME?...`; clips sampled at fps; heat "
      "weights when it has none. Loader warnings become Python warnings. progress(stage, done, total).");

  py::class_<PySkinner>(m, "Skinner", "A rig's fitted implicit skin; bakes animations with any method.")
      .def(py::init([](const Rig& rig, const py::object& setup, const py::object& progress) {
             SkinSetup s = setup_from(setup);
             Released released;
             PySkinner out;
             const SlotGuard guard(*out.slot, released, progress);
             released.run([&] {
               out.skinner = std::make_shared<Skinner>(rig, s, slot_progress(out.slot));
               out.warnings = fit_warnings(out.skinner->fitted(), out.skinner->setup());
             });
             for (const std::string& w : out.warnings)
               PyErr_WarnEx(PyExc_UserWarning, ("isokit: " + w).c_str(), 1);
             return out;
           }),
           py::arg("rig"), py::arg("setup") = py::none(), py::arg("progress") = py::none(),
           "Fits the rig's parts (setup: a dict or a JSON path of docs/skinning.md, default the isokit "
           "defaults). progress(stage, done, total).")
      .def_property_readonly("fit_seconds",
                             [](const PySkinner& s) { return s.skinner->fitted().fit_seconds(); })
      .def(
          "bake",
          [](const PySkinner& s, const std::string& method, const py::object& clip, const py::object& poses,
             const std::vector<std::string>& bends, const py::object& pose_script, int frames,
             bool self_intersections, const py::object& progress) {
            const Method mth = method_from_string(method);
            const Rig& rig = s.skinner->rig();
            Animation animation;
            if (!poses.is_none()) {
              require(clip.is_none() && bends.empty() && pose_script.is_none(), "bake",
                      "takes poses, a clip, bends or a pose script, not several", "give one");
              animation.poses = poses_from(poses, rig.joints.size());
              animation.description =
                  "poses from Python (" + std::to_string(animation.poses.size()) + " frames)";
            } else {
              AnimationRequest request;
              if (!clip.is_none()) request.clip = clip.cast<std::string>();
              request.bends = bends;
              if (!pose_script.is_none()) request.pose_script = path_of(pose_script);
              request.frames = frames;
              animation = make_animation(rig, request, s.skinner->setup().substeps.max_step_rad);
              for (const std::string& w : animation.warnings)
                PyErr_WarnEx(PyExc_UserWarning, ("isokit: " + w).c_str(), 1);
            }
            BakeOptions bo;
            bo.self_intersections = self_intersections;
            Released released;
            const SlotGuard guard(*s.slot, released, progress);
            PyResult out{s.skinner, {}, animation.description, 30};
            released.run([&] { out.result = s.skinner->bake(mth, animation.poses, bo); });
            return out;
          },
          py::arg("method") = std::string(to_string(kDefaultMethod)), py::kw_only(),
          py::arg("clip") = py::none(), py::arg("poses") = py::none(),
          py::arg("bends") = std::vector<std::string>{}, py::arg("pose_script") = py::none(),
          py::arg("frames") = 31, py::arg("self_intersections") = true, py::arg("progress") = py::none(),
          "Bakes one animation with `method` (lbs, dqs, ddm, cor, implicit2013, tracking2014): a clip by "
          "name, "
          "bends ['JOINT:AXIS:DEGREES'], a pose script path, or poses (frames, joints, 4, 4); none plays "
          "the rig's only clip. As `isokit-skin bake`.");

  py::class_<PyResult>(m, "BakeResult", "The frames and metrics of one bake.")
      .def_property_readonly("method",
                             [](const PyResult& r) { return std::string(to_string(r.result.method)); })
      .def_property_readonly(
          "frames",
          [](const PyResult& r) {
            const auto& f = r.result.frames;
            const py::ssize_t v = f.empty() ? 0 : f[0].rows();
            py::array_t<float> out({static_cast<py::ssize_t>(f.size()), v, py::ssize_t{3}});
            float* d = out.mutable_data();
            for (const auto& p : f) {
              std::memcpy(d, p.data(), static_cast<std::size_t>(p.size()) * sizeof(float));
              d += p.size();
            }
            return out;
          },
          "Welded positions per frame (frames, V, 3) float32.")
      .def_property_readonly("mean_ms", [](const PyResult& r) { return r.result.mean_ms; })
      .def(
          "metrics",
          [](const PyResult& r) {
            const std::string text = metrics_json(r.skinner->rig(), {r.result}, r.context());
            return py::module_::import("json").attr("loads")(text);
          },
          "The metrics of `isokit-skin bake --metrics` as a dict (docs/skinning-metrics.md).")
      .def(
          "write_glb",
          [](const PyResult& r, const py::object& path) {
            write_baked_glb(r.skinner->rig(), r.result.frames, r.fps, path_of(path));
          },
          py::arg("path"), "The baked glTF (one morph target per frame), as `isokit-skin bake --glb`.")
      .def(
          "write_pc2",
          [](const PyResult& r, const py::object& path) {
            write_pc2(r.skinner->rig(), r.result.frames, path_of(path));
          },
          py::arg("path"),
          "The frames as a PC2 point cache (file vertex order), as `isokit-skin bake --pc2`.");
}

}  // namespace isokit::python
