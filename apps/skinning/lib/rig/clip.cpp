// SPDX-License-Identifier: MIT
// Clips: frames sampled from a file's key tracks when a command needs them (clip_keys.h).
#include <algorithm>
#include <cmath>

#include "isokit/core/error.h"
#include "rig/clip_keys.h"

namespace isokit::skinning {

Trs decompose(const Affine& a) {
  Trs out;
  out.t = a.translation();
  Eigen::Matrix3d rot;
  Eigen::Matrix3d scale;
  a.computeRotationScaling(&rot, &scale);
  out.r = Eigen::Quaterniond(rot).normalized();
  out.s = scale.diagonal();
  return out;
}

Affine compose(const Trs& x) {
  Affine a = Affine::Identity();
  a.translate(x.t);
  a.rotate(x.r.normalized());
  a.scale(x.s);
  return a;
}

namespace {

Eigen::Vector3d blend(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double u) {
  return (1 - u) * a + u * b;
}

Eigen::Quaterniond blend(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double u) {
  return a.slerp(u, b);
}

}  // namespace

template <class Value>
Value KeyTrack<Value>::at(double t, const Value& fallback) const {
  const std::size_t n = time.size();
  if (n == 0) return fallback;
  if (t <= time[0]) return value[0];
  if (t >= time[n - 1]) return value[n - 1];
  const auto b = static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), t) - time.begin());
  const std::size_t a = b - 1;
  const double span = time[b] - time[a];
  const double u = span > 0 ? (t - time[a]) / span : 0.0;
  return blend(value[a], value[b], u);
}

template struct KeyTrack<Eigen::Vector3d>;
template struct KeyTrack<Eigen::Quaterniond>;

std::size_t ClipKeys::frame_count(double fps) const {
  return static_cast<std::size_t>(std::max(std::ceil(last_seconds * fps - 1e-3), 0.0)) + 1;
}

std::vector<Affine> ClipKeys::sample(double fps, std::size_t frame) const {
  const double ticks = std::min(static_cast<double>(frame) / fps, last_seconds) * ticks_per_second;
  const std::size_t n = nodes.size();
  std::vector<Affine> local(n, Affine::Identity());
  std::vector<Affine> world(n, Affine::Identity());
  for (std::size_t i = 0; i < n; ++i) {
    const Node& node = nodes[i];
    if (!node.relevant) continue;
    if (!node.keyed) {
      local[i] = node.local;
    } else {
      Trs x;
      x.t = node.translation.at(ticks, node.rest.t);
      x.r = node.rotation.at(ticks, node.rest.r);
      x.s = node.scale.at(ticks, node.rest.s);
      local[i] = compose(x);
    }
    world[i] = node.parent >= 0 ? Affine(world[static_cast<std::size_t>(node.parent)] * local[i]) : local[i];
  }
  // Joint transforms relative to their parent joints.
  std::vector<Affine> pose(joint_node.size());
  for (std::size_t j = 0; j < joint_node.size(); ++j) {
    const auto node = static_cast<std::size_t>(joint_node[j]);
    const int pj = joint_parent[j];
    if (pj < 0)
      pose[j] = world[node];
    else if (nodes[node].parent == joint_node[static_cast<std::size_t>(pj)])
      pose[j] = local[node];
    else
      pose[j] =
          world[static_cast<std::size_t>(joint_node[static_cast<std::size_t>(pj)])].inverse(Eigen::Affine) *
          world[node];
  }
  return pose;
}

std::size_t ClipKeys::bytes() const {
  std::size_t b = sizeof(ClipKeys) + (joint_node.size() + joint_parent.size()) * sizeof(int);
  for (const Node& n : nodes)
    b += sizeof(Node) + (n.translation.time.size() + n.scale.time.size()) * (sizeof(double) * 4) +
         n.rotation.time.size() * (sizeof(double) * 5);
  return b;
}

std::size_t Clip::frame_count() const {
  if (!local.empty() || keys == nullptr) return local.size();
  return keys->frame_count(fps);
}

double Clip::seconds() const {
  const std::size_t n = frame_count();
  return n > 0 ? static_cast<double>(n - 1) / fps : 0.0;
}

std::vector<std::vector<Affine>> clip_frames(const Clip& clip) {
  if (!clip.local.empty() || clip.keys == nullptr) return clip.local;
  const std::size_t frames = clip.keys->frame_count(clip.fps);
  const std::size_t joints = std::max<std::size_t>(clip.keys->joint_node.size(), 1);
  require(static_cast<double>(frames) * static_cast<double>(joints) <= static_cast<double>(kMaxClipSamples),
          "clip '" + clip.name + "'",
          "lasts " + format_number(clip.keys->last_seconds) + " s: " + std::to_string(frames) + " frames x " +
              std::to_string(joints) + " joints at " + format_number(clip.fps) + " fps, more than the " +
              std::to_string(kMaxClipSamples) + " joint transforms a clip may be sampled into (512 MiB)",
          "sample it at a lower --fps, or cut the clip in a DCC");
  std::vector<std::vector<Affine>> out;
  out.reserve(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    out.push_back(clip.keys->sample(clip.fps, f));
    for (const Affine& a : out.back())
      require(a.matrix().allFinite(), "clip '" + clip.name + "' frame " + std::to_string(f),
              "a joint transform is not finite", "fix the animation's keys and export again");
  }
  return out;
}

void sample_clips(Rig& rig) {
  for (Clip& clip : rig.clips)
    if (clip.local.empty() && clip.keys != nullptr) clip.local = clip_frames(clip);
}

}  // namespace isokit::skinning
