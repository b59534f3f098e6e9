// SPDX-License-Identifier: MIT
/// \file
/// The skinning viewer's model (`isokit-skin view`, docs/skinning.md): a rig posed by hand or by a
/// clip, skinned by one method (and a second one beside it), with what the overlays and the
/// statistics panel show. No drawing: the window reads the queries and calls the edits, and the
/// unit tests drive the same calls.
///
/// Two sources of poses:
/// - **Editing** (the default): each joint's rotation from its rest pose, as angles about its
///   local x, y and z axes in that order (the pose-script convention, `save_pose_script`), set by
///   sliders. An edit is one undo step; a slider drag (`begin_drag` ... `end_drag`) is one step
///   however many values it set. The implicit methods follow the edits as a sequence of frames
///   (the 2014 tracker is incremental): each shown pose is the next frame of one FrameBaker.
/// - **A clip** (`play_clip`): frame f is the f-th frame of `Skinner::bake` over the clip, bit for
///   bit: frames are baked from the clip's start in order and cached per method, so scrubbing
///   back is free and forward bakes only the frames not yet cached.
///
/// Threads: every member is called from one thread (the window's). Without
/// `ViewerOptions::background` a call that needs new frames returns when they are baked. With
/// it, one worker thread bakes: an edit or a frame change posts a request (a newer one replaces
/// a request not yet started: a slider drag faster than the tracker skips poses, the tracker then
/// sub-steps over the jump), and `poll()` (once per drawn frame) publishes what the worker
/// finished; until then the queries show the last finished frame (`pending()`). An edited pose is
/// shown after a short first part of its solve (`ViewerOptions::edit_slice_ms`) and again when the
/// rest is done: the skin follows a drag at once and settles when the pose rests. The worker alone
/// uses the skinner and the bakers (nothing else may use that skinner while the model lives, but
/// between `wait_idle()` and the next request); the 2014 field, which the overlays read, is built
/// before it starts.
#pragma once

#include <array>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "isokit/skinning/pipeline.h"

namespace isokit::viewer {

using skinning::Method;
using skinning::Pose;

/// Options of the viewer model.
struct ViewerOptions {
  /// Count self-intersecting triangle pairs for the overlay and the statistics (the slowest
  /// metric). Default true.
  bool self_intersections{true};
  std::size_t grain{1024};  ///< parallel grain of the bakes (0 = serial, same results)
  /// Bake on a worker thread (see the file comment); the window sets it. Default false.
  bool background{false};
  /// In the background, the tracking2014 frame of an edit is shown after at most this long (ms,
  /// wall clock; default 3; 0 = whole, one call as `bake`): the tracker's relaxation is cut short
  /// then (or at once by a newer edit), the frame published, and the rest of the whole bake's
  /// iterations run at the same pose in a second call, published too, unless a newer edit comes
  /// first. Clips are baked whole (their frames equal `bake`'s).
  double edit_slice_ms{3.0};
};

/// Per-vertex and per-triangle flags of the shown frame, for the overlays.
struct Overlays {
  std::vector<std::uint8_t> contact;       ///< per vertex: the method's contact flag (implicit methods)
  std::vector<float> mask;                 ///< per vertex: the relaxation mask in use (1 = tracked)
  std::vector<float> dqs_distance;         ///< per vertex: distance to DQS's position, rig units
  std::vector<std::uint8_t> inverted;      ///< per triangle: inverted w.r.t. the field (2014 tree)
  std::vector<std::uint8_t> intersecting;  ///< per triangle: in a self-intersecting pair
  /// Per triangle: bounds a region the skin encloses twice that it did not at rest
  /// (interpenetration, skinning::new_overlap_triangles).
  std::vector<std::uint8_t> overlap;
  /// Per triangle: folded (turned by more than 90° from its rest normal carried by the skinning
  /// blend, skinning/folds.h) and not folded at rest: what `FrameMetrics::folded_new` counts.
  std::vector<std::uint8_t> folded;
};

class ViewerModel {
 public:
  /// A viewer of `skinner`'s rig, at the rest pose, editing, with `method`.
  explicit ViewerModel(std::shared_ptr<skinning::Skinner> skinner, Method method = skinning::kDefaultMethod,
                       ViewerOptions options = {});
  ~ViewerModel();
  ViewerModel(const ViewerModel&) = delete;
  ViewerModel& operator=(const ViewerModel&) = delete;

  const skinning::Rig& rig() const;

  // ---- Joints.
  /// The selected joint, -1 for none.
  int selected_joint() const { return selected_; }
  /// Selects joint `j` (-1: none). \throw InputError for another index.
  void select_joint(int j);
  /// The joint nearest to the ray `origin + t dir` (t ≥ 0) within `radius` of it, at the shown
  /// pose, or -1.
  int pick_joint(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius) const;
  /// World positions of the joints at the shown pose.
  std::vector<Eigen::Vector3d> joint_positions() const;

  // ---- Editing (ends clip playback).
  /// The joint's rotation from its rest pose: degrees about its local x, y, z (in that order).
  std::array<double, 3> joint_angles(int j) const;
  /// Sets it (one undo step, or part of the drag in progress) and bakes the new pose.
  /// \throw InputError for a bad joint or a non-finite angle.
  void set_joint_angles(int j, const std::array<double, 3>& degrees);
  /// A slider drag: the edits until end_drag are one undo step.
  void begin_drag();
  void end_drag();
  bool dragging() const { return dragging_; }
  /// Every joint back to its rest pose (one undo step).
  void reset_pose();
  bool can_undo() const { return !undo_.empty(); }
  bool can_redo() const { return !redo_.empty(); }
  void undo();
  void redo();
  /// Writes the edited pose as a pose script (`isokit-skin bake --pose-script`: one key, frame 0,
  /// each turned joint's [["x", a], ["y", b], ["z", c]]) atomically. \throw InputError naming the file.
  void save_pose_script(const std::string& path) const;
  /// The edited pose (local joint transforms).
  Pose edited_pose() const;

  // ---- Clips.
  std::vector<std::string> clips() const;
  /// Plays clip `name` from frame 0 (bakes it). \throw InputError listing the clips.
  void play_clip(const std::string& name);
  /// The clip played ("" when editing).
  const std::string& clip() const { return clip_; }
  int frame_count() const { return static_cast<int>(clip_poses_.size()); }
  int frame() const { return frame_; }
  /// Shows frame `f` (clamped) of the clip, baking the frames before it not yet cached.
  void set_frame(int f);
  /// Back to editing, at the last edited pose.
  void stop_clip();
  /// Bakes every frame of the clip played by `method()` (the cached frames and the rest) and
  /// writes them as `isokit-skin bake --out` does (one morph target per frame, at the clip's fps);
  /// the shown frame stays. Returns when written. \throw InputError without a clip, or naming the
  /// file.
  void export_clip(const std::string& glb_path);

  // ---- Methods.
  Method method() const { return method_; }
  void set_method(Method m);
  /// A second method shown beside the first (none: one view).
  const std::optional<Method>& compare() const { return compare_; }
  void set_compare(std::optional<Method> m);

  // ---- The shown frame.
  /// The shown frame's welded positions by `method()`, and by `compare()` when set (else null);
  /// in the background, by the methods of the last published frame until the worker catches up.
  const track::Positions& positions() const;
  const track::Positions* compare_positions() const;
  /// Statistics and metrics of the shown frame by `method()` (in the background the metrics of a
  /// frame baked while a newer request waited are skipped: `metrics_shown()` is false).
  const skinning::FrameStats& stats() const;
  bool metrics_shown() const;
  /// Overlays of the shown frame by `method()` (computed on first call per frame).
  const Overlays& overlays();
  /// Frames baked so far (editing steps and clip frames, every method): for tests and the panel.
  long frames_baked() const;

  // ---- Background baking (ViewerOptions::background).
  /// Publishes the frames the worker finished; true when the shown frame changed.
  bool poll();
  /// As poll(), after waiting up to `wait_ms` (ms) for the frame of the last request when it is
  /// not shown yet: a window trades a little of its frame rate for a skin closer to the sliders.
  bool poll(double wait_ms);
  /// True while the shown frame is older than the last request.
  bool pending() const { return shown_id_ != request_id_; }
  /// The last request's number and that of the shown frame (each edit or frame change is one).
  long request_id() const { return request_id_; }
  long shown_id() const { return shown_id_; }
  /// Waits until the worker has finished every request, then polls.
  void wait_idle();

 private:
  using History = std::vector<std::vector<std::array<double, 3>>>;  ///< edited poses (angles per joint)
  struct Frame {
    track::Positions positions;
    skinning::FrameStats stats;
    std::vector<std::uint8_t> contact;
    std::vector<std::uint8_t> excluded;  ///< FrameBaker::iso_exclusions, for metrics measured later
    std::vector<float> mask;
    Pose pose;            ///< the pose it was baked at
    bool measured{true};  ///< stats.metrics computed (in the background: skipped while newer requests wait)
    /// The baker's next frame at `pose` (positions, stats and flags).
    void bake(skinning::FrameBaker& baker, const Pose& at, bool with_metrics);
  };
  /// What the shown state needs baked: the edited pose, or a clip frame, for some methods.
  struct Request {
    long id{0};
    std::string clip;
    Pose pose;                                            ///< editing: the edited pose; clip: unused
    std::shared_ptr<const std::vector<Pose>> clip_poses;  ///< clip: its poses (shared, immutable)
    int frame{0};
    std::vector<Method> methods;
  };
  struct Track;  // one method's bakers and clip cache
  Track& track_of(Method m);
  const Frame& shown(Method m) const;
  void refresh();
  std::map<Method, Frame> execute(const Request& r);
  bool refine(const Request& r, std::map<Method, Frame>& frames);
  void bake_edit(Track& t, const Pose& pose);
  void publish(const Request& r, const std::map<Method, Frame>& frames);
  void worker_loop();
  bool newer_request() const;  ///< a request waits, or the model is closing
  void push_undo();
  void step_history(History& from, History& to);
  Pose pose_of(const std::vector<std::array<double, 3>>& angles) const;

  std::shared_ptr<skinning::Skinner> skinner_;
  ViewerOptions options_;
  Method method_;
  std::optional<Method> compare_;
  int selected_{-1};
  std::vector<std::array<double, 3>> angles_;  ///< per joint, the edited pose
  History undo_, redo_;
  bool dragging_{false};
  bool drag_changed_{false};
  std::string clip_;
  std::vector<Pose> clip_poses_;
  int frame_{0};
  std::map<Method, std::unique_ptr<Track>> tracks_;  ///< the baking thread's
  std::map<Method, Frame> shown_;                    ///< the published frames
  std::vector<Method> shown_methods_;                ///< theirs: the method, then the compared one
  std::optional<Overlays> overlays_;
  long request_id_{0}, shown_id_{0};
  std::shared_ptr<const std::vector<Pose>> clip_shared_;  ///< clip_poses_, for the requests
  // Worker (background): the request waiting, the results finished, the counters.
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_, published_;
  std::optional<Request> waiting_;
  struct Finished {
    long id;
    std::vector<Method> methods;
    std::map<Method, Frame> frames;
  };
  std::optional<Finished> finished_;
  bool busy_{false}, stop_{false};
  long frames_baked_{0};
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace isokit::viewer
