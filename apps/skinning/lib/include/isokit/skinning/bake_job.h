// SPDX-License-Identifier: MIT
/// \file
/// A bake as `isokit-skin bake` and `isokit-skin demo` run it, in steps a program can call:
/// the animation a request names (`make_animation`), the warnings a fitted rig deserves
/// (`fit_warnings`), the frame the pictures show (`peak_frame`), the result that is written
/// (`main_result`) and the files written (`write_bake_outputs`).
#pragma once

#include <string>
#include <vector>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/report.h"
#include "isokit/skinning/views.h"

namespace isokit::skinning {

/// What to animate: at most one of a clip, bends, or a pose script; none plays the rig's only
/// clip (several clips: the error lists them).
struct AnimationRequest {
  std::string clip;  ///< a clip of the rig (or of `clip_file`), by name
  /// An animation file (a skeleton and clips, no mesh needed) whose clip is retargeted onto the
  /// rig by joint name (`retarget_clip`); with `clip` empty its only clip.
  std::string clip_file;
  double fps{30};                  ///< sampling rate of `clip_file`'s clips
  std::vector<std::string> bends;  ///< `JOINT:AXIS:DEGREES`, bent from rest to the angle and back
  std::string pose_script;         ///< path of a JSON pose script (docs/skinning.md)
  int frames{31};                  ///< frames of a bend animation (rest, peak, rest)
};

/// The poses of a request, with what a report calls them.
struct Animation {
  std::vector<Pose> poses;            ///< local joint transforms per frame
  std::vector<BendSpec> bends;        ///< the parsed bends (empty for a clip or a pose script)
  std::string description;            ///< e.g. "--bend LeftLeg:x:150 (31 frames)"
  std::vector<std::string> warnings;  ///< e.g. joints a clip file does not match, one line each
};

/// \throw InputError for more than one source or `frames` outside [3, 100000] (cheap: check
/// before loading a rig).
void check_animation_request(const AnimationRequest& request);

/// \throw InputError as `check_animation_request`, or naming the bad bend / clip / file, or
/// when no source is given and the rig has no clip or several (listed).
/// `max_step_rad` > 0 is mentioned in a bend animation's description.
Animation make_animation(const Rig& rig, const AnimationRequest& request, double max_step_rad = 0);

/// Warnings about a fitted rig, one line each: joints with vertices but no primitive, and limbs
/// made of parts of fewer than `setup.fold_repair_min_part_vertices` vertices (under-resolved:
/// docs/skinning.md, "Low-poly rigs").
std::vector<std::string> fit_warnings(const FittedRig& fitted, const SkinSetup& setup);

/// The frame whose pose is rotated farthest from the first (the first such frame).
int peak_frame(const std::vector<Pose>& poses);

/// The result of `method` (the one whose bake is written). \throw InputError when absent.
const BakeResult& main_result(const std::vector<BakeResult>& results, Method method);

/// Where a bake runs. `kCpu` is the reference (TBB); `kCuda` needs a CUDA build, a usable device
/// and the device tracker (issue 22: not written yet, so `check_device` refuses it for now).
enum class Device { kCpu, kCuda };

/// \throw InputError listing the devices for an unknown name.
Device device_from_string(const std::string& s);

/// \throw InputError naming why `device` cannot run a bake here (no CUDA build, no usable device,
/// no device tracker); nothing for `kCpu`. Cheap: check before loading a rig.
void check_device(Device device);

/// Where a bake's outputs go; an empty path writes nothing.
struct BakeOutputs {
  std::string glb;         ///< the main result, one morph target per frame
  std::string metrics;     ///< the metrics JSON of every result
  std::string render_dir;  ///< contact sheet and one PNG per method and view
  std::string ply_dir;     ///< one PLY per frame of the main result
  std::string pc2;         ///< the main result as a PC2 point cache (file vertex order)
};

/// \throw InputError for a point cache path that is not `*.pc2` or is a folder (cheap: check
/// before loading a rig; `write_bake_outputs` checks it again before writing anything).
void check_bake_outputs(const BakeOutputs& outputs);

/// Writes the outputs (parent folders created); returns what was written, one line each.
/// \throw InputError naming the path that cannot be written.
std::vector<std::string> write_bake_outputs(const Rig& rig, const std::vector<BakeResult>& results,
                                            const BakeResult& main, const ReportContext& context,
                                            const std::vector<RenderView>& views, const BakeOutputs& outputs);

}  // namespace isokit::skinning
