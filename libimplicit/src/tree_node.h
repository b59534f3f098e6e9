// SPDX-License-Identifier: MIT
// Internal to libimplicit: a composition tree's node, shared by the tree (tree.cpp) and its
// compilation into a program (program.cpp).
#pragma once

#include <cstddef>
#include <memory>

#include "isokit/implicit/tree.h"

namespace isokit::implicit {

struct CompositionTree::Node {
  FieldPtr field;  // leaf
  Rigid3f xf{};
  int id{-1};
  NodeOperator op{};  // inner
  NodeTag tag{};
  std::shared_ptr<const Node> first, second;
  std::size_t nodes{1}, leaves{1};
};

}  // namespace isokit::implicit
