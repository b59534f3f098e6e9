// SPDX-License-Identifier: MIT
/// \file
/// Composition-tree builders from a skeleton (2013 §4.2 and 2014 §4.1). The skeleton is given
/// by parent indices; its topology is walked with Boost.Graph inside the library.
///
/// Bone `i`'s primitive is `parts[i]` (local frame) placed by `transforms[i]`; every leaf gets
/// id `i`, so `Pose::set_transform_of(program, i, T)` moves bone `i`. The joint of bone `i` is the
/// one it shares with its parent, and `joints[i]` chooses its operator (ignored for the root).
///
/// Node tags: every node made for joint `i` is tagged `{i, parent[i], joints[i].role}`; its two
/// operands meet across that skeleton edge alone (bone `i` in one operand, its parent in the
/// other). The 2013 tree's `max` nodes over the pairs have the default tag.
#pragma once

#include <vector>

#include "isokit/implicit/tree.h"

namespace isokit::implicit {

struct SkeletonParts {
  std::vector<int> parent;          ///< parent bone, -1 for the single root
  std::vector<FieldPtr> parts;      ///< local primitive per bone
  std::vector<Rigid3f> transforms;  ///< local -> world per bone
};

struct JointSetup {
  NodeOperator op = NodeOperator::max();
  /// 2014 only: compose this bone with its parent at the bottom of the tree (bulge pair).
  bool bulge_pair = false;
  /// What `op` is for at this joint, copied into the tags of the joint's nodes (not read by the
  /// builders or the evaluation). Default: `NodeRole::None`.
  NodeRole role = NodeRole::None;
};

/// 2013: every (parent, child) pair composed by the child's joint operator, then a balanced
/// `max` over all pairs (a single bone gives its leaf). Bones in several pairs appear in several
/// leaves (same field, same id).
/// \throw InputError if sizes differ, a parent index is out of range, there is not exactly one
/// root, or the parents form a cycle.
CompositionTree build_tree_2013(const SkeletonParts& skeleton, const std::vector<JointSetup>& joints);

/// 2014: bulge pairs first (joints with `bulge_pair`, matched greedily from the root down so
/// each bone is in at most one pair), then, from the leaves of the skeleton up, each unit (pair
/// or single bone) is composed with the subtree of every child bone by that child's joint
/// operator (the contact operator by intent), until one root: every bone appears once, and
/// non-neighbouring parts meet through the contact nodes above them.
/// \throw InputError as build_tree_2013.
CompositionTree build_tree_2014(const SkeletonParts& skeleton, const std::vector<JointSetup>& joints);

}  // namespace isokit::implicit
