// SPDX-License-Identifier: MIT
// Random composition trees for the tape tests (CPU and GPU): capsules, optionally sampled into
// grid leaves, composed by every operator kind including a sampled grid operator.
#pragma once

#include <memory>
#include <vector>

#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "isokit/implicit/tree.h"
#include "isokit/operators/analytic.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"
#include "test_util.h"

namespace isokit::test {

namespace ops = isokit::operators;
using implicit::CapsuleField;
using implicit::CompositionTree;
using implicit::FieldPtr;
using implicit::GridField;
using implicit::GridFieldOptions;
using implicit::NodeOperator;

/// A grid operator sampled from the 2013 gradient blend (5 slices in d, 33 nodes per axis).
inline std::shared_ptr<const ops::GridOperator> sampled_blend_grid() {
  const int nd = 5, nf = 33;
  std::vector<float> data(std::size_t(nd * nf * nf));
  for (int k = 0; k < nd; ++k)
    for (int i = 0; i < nf; ++i)
      for (int j = 0; j < nf; ++j)
        data[std::size_t((k * nf + i) * nf + j)] =
            ops::gradient_blend_2013(float(i) / (nf - 1), float(j) / (nf - 1), float(k) / (nd - 1)).g;
  return std::make_shared<const ops::GridOperator>(nd, nf, std::move(data));
}

inline Rigid3f random_rigid(Rng& rng, double spread) {
  const Mat3T<double> R = rng.rotation();
  Rigid3f x;
  for (int i = 0; i < 9; ++i) x.R.m[i] = float(R.m[i]);
  x.t = to_float(rng.vec(-spread, spread));
  return x;
}

inline NodeOperator random_op(Rng& rng, bool constant_d) {
  const auto ctrl = ops::Controller::preset(constant_d ? "constant1" : "blend2013");
  switch (rng.integer(0, 4)) {
    case 0:
      return NodeOperator::max();
    case 1:
      return NodeOperator::sum_blend();
    case 2:
      return NodeOperator::clean_union();
    case 3:
      return NodeOperator::gradient_blend(ctrl);
    default:
      return NodeOperator::grid_operator(sampled_blend_grid(), ctrl, "blend-grid");
  }
}

/// A random tree of `n` capsules spread over a few units (random shape of the tree); every
/// `grid_every`-th capsule (0: none) is sampled into a `grid_n`³ grid (inline grid leaves).
inline CompositionTree random_tree(Rng& rng, int n, bool constant_d, int grid_every = 4, int grid_n = 12) {
  std::vector<CompositionTree> items;
  for (int i = 0; i < n; ++i) {
    const float len = float(rng.uniform(0.3, 1.2)), rad = float(rng.uniform(0.15, 0.4));
    FieldPtr cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, len}, rad);
    if (grid_every > 0 && i % grid_every == grid_every - 1)
      cap = std::make_shared<const GridField>(*cap, Box3f{}, GridFieldOptions{grid_n, 0});  // grid leaf
    items.push_back(CompositionTree::leaf(cap, random_rigid(rng, 1.5), i));
  }
  while (items.size() > 1) {
    const std::size_t a = std::size_t(rng.integer(0, int(items.size()) - 1));
    CompositionTree ta = items[a];
    items.erase(items.begin() + long(a));
    const std::size_t b = std::size_t(rng.integer(0, int(items.size()) - 1));
    CompositionTree tb = items[b];
    items.erase(items.begin() + long(b));
    items.push_back(CompositionTree::node(random_op(rng, constant_d), ta, tb));
  }
  return items[0];
}

}  // namespace isokit::test
