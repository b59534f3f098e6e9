// SPDX-License-Identifier: MIT
// The skinning viewer's model (model.h): edited poses with undo, clips baked once per method,
// the shown frame's statistics and overlays.
#include "isokit/viewer/model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/rig_io.h"

namespace isokit::viewer {

using skinning::Affine;
using skinning::FrameBaker;
using skinning::Rig;

/// One method's bakers: the editing one (the edited poses as a sequence of frames) and the clip's
/// (frames cached from the clip's start).
struct ViewerModel::Track {
  std::unique_ptr<FrameBaker> edit_baker;
  Frame edit_frame;
  // A sliced edit (ViewerOptions::edit_slice_ms): the iterations its pose may still spend, whether
  // its solve is unfinished.
  int iterations_left{0};
  bool unfinished{false};
  std::unique_ptr<FrameBaker> clip_baker;
  std::string clip;
  std::vector<Frame> clip_frames;
};

namespace {

/// The rotation of `degrees` about local x, then y, then z (the pose-script order).
Eigen::Matrix3d rotation_of(const std::array<double, 3>& degrees) {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int a = 0; a < 3; ++a)
    r = r *
        Eigen::AngleAxisd(degrees[std::size_t(a)] * kPi / 180.0, Eigen::Vector3d::Unit(a)).toRotationMatrix();
  return r;
}

skinning::BakeOptions bake_options(const ViewerOptions& o) {
  skinning::BakeOptions b;
  b.metrics = !o.background;  // in the background: measured only when no newer request waits
  b.self_intersections = o.self_intersections;
  b.grain = o.grain;
  return b;
}

}  // namespace

ViewerModel::ViewerModel(std::shared_ptr<skinning::Skinner> skinner, Method method, ViewerOptions options)
    : skinner_(std::move(skinner)), options_(options), method_(method) {
  require(skinner_ != nullptr, "viewer", "has no rig", "open a rig first");
  angles_.assign(rig().joints.size(), {0.0, 0.0, 0.0});
  if (options_.background) {
    // Built now: the overlays read it on the window's thread, the worker must not build it then
    // (the 2013 tree, which only the worker uses, is built there when a method needs it).
    skinner_->field(skinning::TreeKind::k2014);
    worker_ = std::thread([this] { worker_loop(); });
  }
  refresh();
  if (options_.background) wait_idle();  // the first frame is there before the first draw
}

ViewerModel::~ViewerModel() {
  if (worker_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    worker_.join();
  }
}

long ViewerModel::frames_baked() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_baked_;
}

const Rig& ViewerModel::rig() const {
  return skinner_->rig();
}

void ViewerModel::select_joint(int j) {
  require(j >= -1 && j < static_cast<int>(rig().joints.size()), "viewer: joint " + std::to_string(j),
          "does not exist",
          "select one of the rig's " + std::to_string(rig().joints.size()) + " joints, or -1");
  selected_ = j;
}

std::vector<Eigen::Vector3d> ViewerModel::joint_positions() const {
  const Pose pose = clip_.empty() ? edited_pose() : clip_poses_[std::size_t(frame_)];
  const std::vector<Affine> world = skinning::world_transforms(rig(), pose);
  std::vector<Eigen::Vector3d> out;
  for (const Affine& w : world) out.push_back(w.translation());
  return out;
}

int ViewerModel::pick_joint(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius) const {
  const Eigen::Vector3d d = dir.normalized();
  int best = -1;
  double best_t = INFINITY;
  const std::vector<Eigen::Vector3d> at = joint_positions();
  for (std::size_t j = 0; j < at.size(); ++j) {
    const double t = std::max(0.0, (at[j] - origin).dot(d));
    if ((origin + t * d - at[j]).norm() <= radius && t < best_t) best = static_cast<int>(j), best_t = t;
  }
  return best;
}

std::array<double, 3> ViewerModel::joint_angles(int j) const {
  require(j >= 0 && j < static_cast<int>(angles_.size()), "viewer: joint " + std::to_string(j),
          "does not exist", "use an index into the rig's joints");
  return angles_[std::size_t(j)];
}

Pose ViewerModel::pose_of(const std::vector<std::array<double, 3>>& angles) const {
  Pose pose = skinning::rest_pose(rig());
  for (std::size_t j = 0; j < pose.size(); ++j)
    if (angles[j] != std::array<double, 3>{0.0, 0.0, 0.0}) {
      Affine r = Affine::Identity();
      r.linear() = rotation_of(angles[j]);
      pose[j] = pose[j] * r;
    }
  return pose;
}

Pose ViewerModel::edited_pose() const {
  return pose_of(angles_);
}

void ViewerModel::push_undo() {
  undo_.push_back(angles_);
  redo_.clear();
}

void ViewerModel::set_joint_angles(int j, const std::array<double, 3>& degrees) {
  joint_angles(j);  // checks j
  for (double a : degrees)
    require(std::isfinite(a), "viewer: joint " + std::to_string(j) + " angle", "is not finite",
            "give degrees");
  clip_.clear();
  if (degrees == angles_[std::size_t(j)]) return;
  if (!dragging_ || !drag_changed_) push_undo();
  if (dragging_) drag_changed_ = true;
  angles_[std::size_t(j)] = degrees;
  refresh();
}

void ViewerModel::begin_drag() {
  dragging_ = true;
  drag_changed_ = false;
}

void ViewerModel::end_drag() {
  dragging_ = false;
  drag_changed_ = false;
}

void ViewerModel::reset_pose() {
  clip_.clear();
  const std::vector<std::array<double, 3>> rest(angles_.size(), {0.0, 0.0, 0.0});
  if (angles_ == rest) return;
  end_drag();
  push_undo();
  angles_ = rest;
  refresh();
}

// Undo and redo: the last pose of `from` becomes the edited one, the edited one goes to `to`.
void ViewerModel::step_history(History& from, History& to) {
  if (from.empty()) return;
  end_drag();
  clip_.clear();
  to.push_back(angles_);
  angles_ = from.back();
  from.pop_back();
  refresh();
}

void ViewerModel::undo() {
  step_history(undo_, redo_);
}

void ViewerModel::redo() {
  step_history(redo_, undo_);
}

void ViewerModel::save_pose_script(const std::string& path) const {
  using nlohmann::json;
  json joints = json::object();
  for (std::size_t j = 0; j < angles_.size(); ++j) {
    const std::array<double, 3>& a = angles_[j];
    if (a == std::array<double, 3>{0.0, 0.0, 0.0}) continue;
    json turns = json::array();
    for (int c = 0; c < 3; ++c)
      turns.push_back(json::array({std::string(1, char('x' + c)), a[std::size_t(c)]}));
    joints[rig().joints[j].name] = turns;
  }
  json key = json::object();
  key["frame"] = 0;
  key["joints"] = joints;
  json doc = json::object();
  doc["keys"] = json::array({key});
  write_text_file_atomically(path, doc.dump(2) + "\n");
}

std::vector<std::string> ViewerModel::clips() const {
  std::vector<std::string> names;
  for (const skinning::Clip& c : rig().clips) names.push_back(c.name);
  return names;
}

void ViewerModel::play_clip(const std::string& name) {
  std::vector<Pose> poses = skinning::clip_animation(rig(), name);  // throws listing the clips
  require(!poses.empty(), "viewer: clip '" + name + "'", "has no frames", "choose another clip");
  clip_poses_ = std::move(poses);
  clip_shared_ = std::make_shared<const std::vector<Pose>>(clip_poses_);
  end_drag();
  clip_ = name;
  frame_ = 0;
  refresh();
}

void ViewerModel::set_frame(int f) {
  if (clip_.empty()) return;
  frame_ = std::clamp(f, 0, frame_count() - 1);
  refresh();
}

void ViewerModel::stop_clip() {
  if (clip_.empty()) return;
  clip_.clear();
  refresh();
}

void ViewerModel::export_clip(const std::string& glb_path) {
  require(!clip_.empty(), "viewer: export", "no clip is playing", "choose a clip first");
  const int shown_frame = frame_;
  frame_ = frame_count() - 1;
  refresh();  // bakes (or asks the worker for) every frame up to the last
  wait_idle();
  std::vector<track::Positions> frames;
  for (const Frame& f : tracks_.at(method_)->clip_frames)
    frames.push_back(f.positions);  // the worker is idle
  const auto clip = std::find_if(rig().clips.begin(), rig().clips.end(),
                                 [&](const skinning::Clip& c) { return c.name == clip_; });
  skinning::write_baked_glb(rig(), frames, clip->fps, glb_path);
  frame_ = shown_frame;
  refresh();
  wait_idle();
}

void ViewerModel::set_method(Method m) {
  method_ = m;
  refresh();
}

void ViewerModel::set_compare(std::optional<Method> m) {
  compare_ = m;
  refresh();
}

ViewerModel::Track& ViewerModel::track_of(Method m) {
  std::unique_ptr<Track>& t = tracks_[m];
  if (!t) t = std::make_unique<Track>();
  return *t;
}

// The shown state as a request: baked now, or posted to the worker.
void ViewerModel::refresh() {
  overlays_.reset();
  Request r;
  r.id = ++request_id_;
  r.methods = {method_};
  if (compare_ && *compare_ != method_) r.methods.push_back(*compare_);
  r.clip = clip_;
  if (clip_.empty()) {
    r.pose = edited_pose();
  } else {
    r.clip_poses = clip_shared_;
    r.frame = frame_;
  }
  if (!options_.background) {
    shown_ = execute(r);
    shown_methods_ = r.methods;
    shown_id_ = r.id;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_ = std::move(r);  // replaces a request not yet started
  }
  wake_.notify_all();
}

namespace {

/// Adds the work of a call that continued a frame at its pose to the frame's statistics.
void add_slice(const skinning::FrameStats& slice, skinning::FrameStats& st) {
  st.ms += slice.ms;
  st.iterations += slice.iterations;
  st.vertex_updates += slice.vertex_updates;
  st.field_evaluations += slice.field_evaluations;
  st.axis_guard_moves += slice.axis_guard_moves;
  st.oriented_vertices += slice.oriented_vertices;
  st.lost_vertices = slice.lost_vertices;
  st.tracker_calls += slice.tracker_calls;
  st.capped_calls = slice.capped_calls;  // whether the pose's solve is still unfinished
  st.call_iterations.insert(st.call_iterations.end(), slice.call_iterations.begin(),
                            slice.call_iterations.end());
}

}  // namespace

void ViewerModel::Frame::bake(FrameBaker& baker, const Pose& at, bool with_metrics) {
  positions = baker.next(at, &stats);
  contact = baker.contacts() ? *baker.contacts() : std::vector<std::uint8_t>{};
  excluded = baker.iso_exclusions();
  mask = baker.mask();
  pose = at;
  measured = with_metrics;
}

// The edited pose's frame by one method: whole, or (sliced: tracking2014 in the background) cut
// short after ViewerOptions::edit_slice_ms or by a newer request, its solve left to refine().
void ViewerModel::bake_edit(Track& t, const Pose& pose) {
  FrameBaker& baker = *t.edit_baker;
  const bool sliced =
      options_.background && options_.edit_slice_ms > 0 && baker.method() == Method::kTracking2014;
  Frame& f = t.edit_frame;
  if (!sliced) {
    f.bake(baker, pose, !options_.background);
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  baker.set_iteration_cap(0);
  baker.set_interrupt([this, start] {  // shown when the time is up or a newer edit waits
    const std::chrono::duration<double, std::milli> spent = std::chrono::steady_clock::now() - start;
    return spent.count() >= options_.edit_slice_ms || newer_request() ? track::TrackInterrupt::kStop
                                                                      : track::TrackInterrupt::kContinue;
  });
  f.bake(baker, pose, false);
  baker.set_interrupt({});
  // The rest of the whole bake's work: `tracker.max_iterations` per sub-step.
  t.iterations_left = skinner_->setup().tracker.max_iterations * f.stats.substeps - f.stats.iterations;
  t.unfinished = f.stats.capped_calls > 0 && t.iterations_left > 0;
}

// The rest of each unfinished edit's solve in `r`: one more tracker call at the same pose (the
// worker; abandoned for a newer request); false when there was none or it was abandoned.
bool ViewerModel::refine(const Request& r, std::map<Method, Frame>& frames) {
  if (!r.clip.empty()) return false;
  bool any = false;
  for (const Method m : r.methods) {
    Track& t = track_of(m);
    if (!t.unfinished) continue;
    t.unfinished = false;
    FrameBaker& baker = *t.edit_baker;
    baker.set_iteration_cap(t.iterations_left);
    baker.set_interrupt([this] {  // a newer edit: its frame starts where this one stopped
      return newer_request() ? track::TrackInterrupt::kAbandon : track::TrackInterrupt::kContinue;
    });
    Frame& f = t.edit_frame;
    const skinning::FrameStats first = f.stats;
    f.bake(baker, r.pose, false);
    baker.set_interrupt({});
    baker.set_iteration_cap(0);
    const skinning::FrameStats rest = f.stats;
    f.stats = first;
    add_slice(rest, f.stats);
    if (rest.abandoned) return false;  // the shown frame stays the first part's
    frames[m] = f;
    any = true;
  }
  return any;
}

// Bakes request `r` for each of its methods (on the thread that owns the bakers).
std::map<Method, ViewerModel::Frame> ViewerModel::execute(const Request& r) {
  std::map<Method, Frame> out;
  long baked = 0;
  for (const Method m : r.methods) {
    Track& t = track_of(m);
    if (r.clip.empty()) {
      if (!t.edit_baker) t.edit_baker = std::make_unique<FrameBaker>(*skinner_, m, bake_options(options_));
      bake_edit(t, r.pose);
      ++baked;
      out[m] = t.edit_frame;
      continue;
    }
    if (t.clip != r.clip) {
      t.clip = r.clip;
      t.clip_frames.clear();
      t.clip_baker = std::make_unique<FrameBaker>(*skinner_, m, bake_options(options_));
    }
    while (static_cast<int>(t.clip_frames.size()) <= r.frame) {
      Frame f;
      f.bake(*t.clip_baker, (*r.clip_poses)[t.clip_frames.size()], !options_.background);
      ++baked;
      t.clip_frames.push_back(std::move(f));
    }
    out[m] = t.clip_frames[std::size_t(r.frame)];
  }
  std::lock_guard<std::mutex> lock(mutex_);
  frames_baked_ += baked;
  return out;
}

// The worker: takes the waiting request, bakes it, leaves the frames for poll(); when no newer
// request comes within kMeasureDelay, measures those frames (the slow metrics: self-intersections)
// and leaves them again.
void ViewerModel::worker_loop() {
  constexpr auto kMeasureDelay = std::chrono::milliseconds(150);
  for (;;) {
    Request r;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || waiting_.has_value(); });
      if (stop_) return;
      r = std::move(*waiting_);
      waiting_.reset();
      busy_ = true;
    }
    std::map<Method, Frame> frames;
    std::exception_ptr error;
    try {
      frames = execute(r);
      publish(r, frames);
      while (!newer_request() && refine(r, frames)) publish(r, frames);  // sliced edits
    } catch (...) {
      error = std::current_exception();
    }
    bool measure = false;
    if (error) {  // a window waiting in poll(wait_ms) learns of it at once
      {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = error;
      }
      published_.notify_all();
    }
    {
      std::unique_lock<std::mutex> lock(mutex_);
      measure =
          !error && !wake_.wait_for(lock, kMeasureDelay, [this] { return stop_ || waiting_.has_value(); });
      if (!measure) busy_ = false;
    }
    if (measure) {
      try {
        for (auto& [m, f] : frames) {
          f.stats.metrics = skinner_->measure(f.pose, f.positions, options_.self_intersections,
                                              f.excluded.empty() ? nullptr : &f.excluded);
          f.measured = true;
        }
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex_);
      if (error)
        error_ = error;
      else if (!waiting_)
        finished_ = Finished{r.id, r.methods, std::move(frames)};
      busy_ = false;
    }
    idle_.notify_all();
  }
}

void ViewerModel::publish(const Request& r, const std::map<Method, Frame>& frames) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = Finished{r.id, r.methods, frames};
  }
  published_.notify_all();
}

bool ViewerModel::newer_request() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stop_ || waiting_.has_value();
}

bool ViewerModel::poll() {
  std::optional<Finished> done;
  std::exception_ptr error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done.swap(finished_);
    std::swap(error, error_);
  }
  if (error) std::rethrow_exception(error);
  if (!done) return false;
  shown_ = std::move(done->frames);
  shown_methods_ = std::move(done->methods);
  shown_id_ = done->id;
  overlays_.reset();
  return true;
}

bool ViewerModel::poll(double wait_ms) {
  if (options_.background && pending() && wait_ms > 0) {
    std::unique_lock<std::mutex> lock(mutex_);
    published_.wait_for(lock, std::chrono::duration<double, std::milli>(wait_ms),
                        [this] { return error_ || (finished_ && finished_->id == request_id_); });
  }
  return poll();
}

void ViewerModel::wait_idle() {
  if (options_.background) {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return !busy_ && !waiting_.has_value(); });
  }
  poll();
}

const ViewerModel::Frame& ViewerModel::shown(Method m) const {
  const auto it = shown_.find(m);
  require(it != shown_.end(), "viewer", std::string("has no frame of ") + skinning::to_string(m) + " yet",
          "wait for the bake (pending(), poll())");
  return it->second;
}

const track::Positions& ViewerModel::positions() const {
  return shown(shown_methods_.front()).positions;
}

const track::Positions* ViewerModel::compare_positions() const {
  if (!compare_) return nullptr;
  return &shown(shown_methods_.size() > 1 ? shown_methods_[1] : shown_methods_.front()).positions;
}

const skinning::FrameStats& ViewerModel::stats() const {
  return shown(shown_methods_.front()).stats;
}

bool ViewerModel::metrics_shown() const {
  return shown(shown_methods_.front()).measured;
}

const Overlays& ViewerModel::overlays() {
  if (overlays_) return *overlays_;
  const Frame& f = shown(shown_methods_.front());
  const Rig& r = rig();
  const std::size_t nv = static_cast<std::size_t>(r.rest.rows());
  const std::size_t nt = static_cast<std::size_t>(r.triangles.rows());
  Overlays o;
  o.contact = f.contact.empty() ? std::vector<std::uint8_t>(nv, 0) : f.contact;
  o.mask = f.mask.empty() ? std::vector<float>(nv, 1.0f) : f.mask;
  // Distance to DQS at the shown frame's pose.
  const std::vector<Affine> skin = skinning::skinning_matrices(r, f.pose);
  track::Positions dqs;
  skinning::dual_quaternion_blend(r.weights, skin, r.rest, dqs, nullptr, options_.grain);
  o.dqs_distance.resize(nv);
  for (std::size_t v = 0; v < nv; ++v)
    o.dqs_distance[v] = (f.positions.row(Eigen::Index(v)) - dqs.row(Eigen::Index(v))).norm();
  // Inverted triangles: the normal along +∇f at the centroid (the 2014 tree at the pose).
  skinning::SkinField& field = skinner_->field(skinning::TreeKind::k2014);
  const track::FieldFunction fn = field.function(field.pose_of(skin));
  std::vector<Vec3f> centroid(nt), grad(nt);
  std::vector<float> value(nt);
  std::vector<std::uint8_t> unused(nt);
  for (std::size_t k = 0; k < nt; ++k) {
    Eigen::Vector3f c = Eigen::Vector3f::Zero();
    for (int i = 0; i < 3; ++i) c += f.positions.row(r.triangles(Eigen::Index(k), i)).transpose();
    c /= 3.f;
    centroid[k] = Vec3f{c.x(), c.y(), c.z()};
  }
  if (nt > 0) fn(centroid.data(), nt, value.data(), grad.data(), unused.data());
  o.inverted.assign(nt, 0);
  for (std::size_t k = 0; k < nt; ++k) {
    const Eigen::Vector3f a = f.positions.row(r.triangles(Eigen::Index(k), 0)).transpose();
    const Eigen::Vector3f b = f.positions.row(r.triangles(Eigen::Index(k), 1)).transpose();
    const Eigen::Vector3f c = f.positions.row(r.triangles(Eigen::Index(k), 2)).transpose();
    const Eigen::Vector3f n = (b - a).cross(c - a);
    o.inverted[k] = n.dot(Eigen::Vector3f(grad[k].x, grad[k].y, grad[k].z)) > 0.f ? 1 : 0;
  }
  // Self-intersecting triangles.
  o.intersecting.assign(nt, 0);
  if (options_.self_intersections) {
    skinning::SelfIntersectionDetails details;
    skinning::SelfIntersectionOptions so;
    so.max_pairs = static_cast<int>(std::min<std::size_t>(nt * 4, 1u << 20));
    skinning::count_self_intersections(f.positions, r.triangles, &details, so);
    for (const auto& p : details.pairs)
      o.intersecting[std::size_t(p[0])] = o.intersecting[std::size_t(p[1])] = 1;
  }
  // Interpenetration: the triangles bounding new volume enclosed twice.
  o.overlap.assign(nt, 0);
  for (const int t : skinning::new_overlap_triangles(r.rest, f.positions, r.triangles))
    o.overlap[std::size_t(t)] = 1;
  // Folds: turned by more than 90° from the rest normal carried by the skinning blend.
  o.folded.assign(nt, 0);
  if (const skinning::FoldCounter* folds = skinner_->metrics_evaluator().folds()) {
    const std::vector<std::uint8_t> flags = folds->folded(f.positions, skin);
    for (std::size_t k = 0; k < nt; ++k) o.folded[k] = flags[k] && !folds->rest_folded()[k] ? 1 : 0;
  }
  overlays_ = std::move(o);
  return *overlays_;
}

}  // namespace isokit::viewer
