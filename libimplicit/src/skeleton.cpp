// SPDX-License-Identifier: MIT
#include "isokit/implicit/skeleton.h"

#include <boost/graph/adjacency_list.hpp>

#include "isokit/core/error.h"

namespace isokit::implicit {

namespace {

using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS>;

struct Topology {
  explicit Topology(std::size_t n) : g(n) {}
  Graph g;
  int root{-1};
  std::vector<int> discover;  // pre-order from the root
  std::vector<int> finish;    // post-order (children before parents)
};

void topology(const SkeletonParts& s, const std::vector<JointSetup>& joints, Topology& t) {
  const std::size_t n = s.parent.size();
  require(n >= 1, "skeleton", "has no bones", "give at least one bone");
  require(s.parts.size() == n && s.transforms.size() == n && joints.size() == n, "skeleton",
          "parent, parts, transforms and joints must have one entry per bone (" + std::to_string(n) + ")",
          "fill every array");
  for (std::size_t i = 0; i < n; ++i) {
    const int p = s.parent[i];
    require(p >= -1 && p < int(n) && p != int(i), "skeleton bone " + std::to_string(i),
            "has parent " + std::to_string(p), "use -1 for the root or an index of another bone");
    require(s.parts[i] != nullptr, "skeleton bone " + std::to_string(i), "has no primitive", "fit its part");
    if (p < 0) {
      require(t.root < 0, "skeleton bone " + std::to_string(i), "is a second root", "give it a parent");
      t.root = int(i);
    } else {
      boost::add_edge(std::size_t(p), i, t.g);
    }
  }
  require(t.root >= 0, "skeleton", "has no root (the parents form a cycle)", "set one parent to -1");
  // Iterative depth-first walk over the out-edges: pre-order (discover) and post-order (finish).
  bool cycle = false;
  std::vector<int> state(n, 0);  // 0 new, 1 open, 2 finished
  std::vector<std::pair<int, bool>> stack{{t.root, false}};
  while (!stack.empty()) {
    const auto [v, expanded] = stack.back();
    stack.pop_back();
    if (expanded) {
      state[std::size_t(v)] = 2;
      t.finish.push_back(v);
      continue;
    }
    if (state[std::size_t(v)] != 0) {
      cycle = true;
      continue;
    }
    state[std::size_t(v)] = 1;
    t.discover.push_back(v);
    stack.push_back({v, true});
    std::vector<int> children;
    for (auto [e, end] = boost::out_edges(std::size_t(v), t.g); e != end; ++e)
      children.push_back(int(boost::target(*e, t.g)));
    for (auto c = children.rbegin(); c != children.rend(); ++c) stack.push_back({*c, false});
  }
  require(!cycle && t.discover.size() == n, "skeleton",
          "is not one tree (" + std::to_string(n - t.discover.size()) + " bones unreachable from the root)",
          "fix the parent indices");
}

CompositionTree leaf(const SkeletonParts& s, int i) {
  return CompositionTree::leaf(s.parts[std::size_t(i)], s.transforms[std::size_t(i)], i);
}

/// The tag of the node that composes bone `child` with its parent's side.
NodeTag joint_tag(int child, int parent, const std::vector<JointSetup>& joints) {
  return NodeTag{child, parent, joints[std::size_t(child)].role};
}

CompositionTree balanced_max(std::vector<CompositionTree>& items, std::size_t lo, std::size_t hi) {
  if (hi - lo == 1) return items[lo];
  const std::size_t mid = lo + (hi - lo) / 2;
  return CompositionTree::node(NodeOperator::max(), balanced_max(items, lo, mid),
                               balanced_max(items, mid, hi));
}

}  // namespace

CompositionTree build_tree_2013(const SkeletonParts& s, const std::vector<JointSetup>& joints) {
  Topology t(s.parent.size());
  topology(s, joints, t);
  std::vector<CompositionTree> pairs;
  for (int c : t.discover) {
    const int p = s.parent[std::size_t(c)];
    if (p < 0) continue;
    pairs.push_back(
        CompositionTree::node(joints[std::size_t(c)].op, leaf(s, p), leaf(s, c), joint_tag(c, p, joints)));
  }
  if (pairs.empty()) return leaf(s, t.root);
  return balanced_max(pairs, 0, pairs.size());
}

CompositionTree build_tree_2014(const SkeletonParts& s, const std::vector<JointSetup>& joints) {
  Topology t(s.parent.size());
  topology(s, joints, t);
  const std::size_t n = s.parent.size();
  std::vector<int> partner(n, -1);  // bulge partner
  for (int c : t.discover) {
    const int p = s.parent[std::size_t(c)];
    if (p >= 0 && joints[std::size_t(c)].bulge_pair && partner[std::size_t(c)] < 0 &&
        partner[std::size_t(p)] < 0) {
      partner[std::size_t(c)] = p;
      partner[std::size_t(p)] = c;
    }
  }
  auto is_pair_child = [&](int b) {
    const int q = partner[std::size_t(b)];
    return q >= 0 && s.parent[std::size_t(b)] == q;
  };
  std::vector<CompositionTree> sub(n, leaf(s, t.root));  // every entry is assigned below
  for (int b : t.finish) {
    if (is_pair_child(b)) continue;  // composed within its parent's unit
    std::vector<int> members{b};
    CompositionTree unit = leaf(s, b);
    const int q = partner[std::size_t(b)];
    if (q >= 0) {
      unit = CompositionTree::node(joints[std::size_t(q)].op, unit, leaf(s, q), joint_tag(q, b, joints));
      members.push_back(q);
    }
    for (int m : members) {
      for (auto [e, end] = boost::out_edges(std::size_t(m), t.g); e != end; ++e) {
        const int c = int(boost::target(*e, t.g));
        if (c == q && m == b) continue;
        unit = CompositionTree::node(joints[std::size_t(c)].op, unit, sub[std::size_t(c)],
                                     joint_tag(c, m, joints));
      }
    }
    sub[std::size_t(b)] = unit;
  }
  return sub[std::size_t(t.root)];
}

}  // namespace isokit::implicit
