// SPDX-License-Identifier: MIT
/// \file
/// A file's animation as key tracks (io/rig_io_load.cpp builds them), sampled into frames only
/// when a command needs them (`clip_frames`, rig.h): a file of a few kilobytes can declare a clip
/// of hours, and `info` must not sample it.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "isokit/skinning/rig.h"

namespace isokit::skinning {

/// A transform as translation, rotation and scale (how files key joints).
struct Trs {
  Eigen::Vector3d t{Eigen::Vector3d::Zero()};
  Eigen::Quaterniond r{Eigen::Quaterniond::Identity()};
  Eigen::Vector3d s{Eigen::Vector3d::Ones()};
};

Trs decompose(const Affine& a);
Affine compose(const Trs& x);

/// Keys of one transform component: times in ticks, ascending; values.
template <class Value>
struct KeyTrack {
  std::vector<double> time;
  std::vector<Value> value;

  /// The value at `t`: clamped at the ends, linear (slerp for rotations) between keys; `fallback`
  /// without keys.
  Value at(double t, const Value& fallback) const;
};

struct ClipKeys {
  /// One node of the file's hierarchy that the joints' transforms depend on.
  struct Node {
    int parent{-1};        ///< index into `nodes` of its parent when that is relevant, else -1
    bool relevant{false};  ///< a joint or an ancestor of a root joint
    bool keyed{false};     ///< has a channel; otherwise `local` at every frame
    Affine local{Affine::Identity()};
    Trs rest;  ///< `local` decomposed: the value of a component without keys
    KeyTrack<Eigen::Vector3d> translation;
    KeyTrack<Eigen::Quaterniond> rotation;
    KeyTrack<Eigen::Vector3d> scale;
  };

  double ticks_per_second{1};
  double last_seconds{0};         ///< the last key
  std::vector<Node> nodes;        ///< parents before children
  std::vector<int> joint_node;    ///< per joint of the rig: its node
  std::vector<int> joint_parent;  ///< per joint: its parent joint or -1

  /// Frames at `fps` from 0 to `last_seconds`, both ends included (at least 1).
  std::size_t frame_count(double fps) const;
  /// The local joint transforms at frame `frame` of `fps` (times past the last key hold it).
  std::vector<Affine> sample(double fps, std::size_t frame) const;
  /// Bytes the keys take (what a load charges for them).
  std::size_t bytes() const;
};

}  // namespace isokit::skinning
