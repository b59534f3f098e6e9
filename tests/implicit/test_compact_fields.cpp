// SPDX-License-Identifier: MIT
// Field evaluation at memory speed (docs/performance.md, "Field evaluation at memory speed"):
// fixed16 grids against float32 grids within their stated bound, their gradients against finite
// differences, the SSE2 path against the scalar (device) one bit for bit, and the sparse
// evaluator's per-block cull, repeated-leaf sharing and bounded max against the instruction loop
// bit for bit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <memory>
#include <vector>
#include "isokit/operators/grid_operator.h"

#include "isokit/implicit/evaluators.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "isokit/implicit/program_field.h"
#include "isokit/implicit/skeleton.h"
#include "tree_fixtures.h"

using namespace isokit;
using namespace isokit::implicit;
using isokit::test::random_tree;
using isokit::test::sampled_blend_grid;

namespace {

/// Rig-like parts (the local frame of a bone along +z): a limb, a finger, a torso, a flat
/// hand, each with the support width of a fitted part (about its radius).
std::vector<std::shared_ptr<const Field>> rig_like_parts() {
  return {std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.25f, 0.25f),
          std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 0.3f}, 0.04f, 0.04f),
          std::make_shared<const SphereField>(Vec3f{0.1f, -0.2f, 0.3f}, 0.7f, 0.5f),
          std::make_shared<const CapsuleField>(Vec3f{-0.2f, 0, 0}, Vec3f{0.2f, 0, 0.4f}, 0.06f, 0.3f)};
}

Vec3f random_in(test::Rng& rng, const Box3f& b) {
  return {float(rng.uniform(b.lo.x, b.hi.x)), float(rng.uniform(b.lo.y, b.hi.y)),
          float(rng.uniform(b.lo.z, b.hi.z))};
}

GridFieldOptions storage_options(int resolution, GridStorage storage) {
  GridFieldOptions o;
  o.resolution = resolution;
  o.grain = 0;
  o.storage = storage;
  return o;
}

/// Random skeleton-like chain with branches: `bones` capsules, each child starting at its
/// parent's end (a 2013 tree repeats every bone once per pair it is in).
SkeletonParts random_skeleton(test::Rng& rng, int bones, bool grids) {
  SkeletonParts s;
  std::vector<Vec3f> end;
  for (int i = 0; i < bones; ++i) {
    const int parent = i == 0 ? -1 : rng.integer(std::max(0, i - 3), i - 1);
    const Vec3f start = parent < 0 ? Vec3f{0, 0, 0} : end[std::size_t(parent)];
    const Vec3f dir = test::to_float(rng.vec(-0.6, 0.6));
    const float radius = float(rng.uniform(0.1, 0.25));
    FieldPtr part = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, dir, radius);
    if (grids) part = std::make_shared<const GridField>(*part, Box3f{}, GridFieldOptions{16, 0});
    Rigid3f x;
    x.t = start;
    s.parent.push_back(parent);
    s.parts.push_back(part);
    s.transforms.push_back(x);
    end.push_back(start + dir);
  }
  return s;
}

/// Points near a skeleton's bones, in no particular order.
std::vector<Vec3f> points_near(test::Rng& rng, const SkeletonParts& s, std::size_t n) {
  std::vector<Vec3f> pts(n);
  for (Vec3f& p : pts) {
    const std::size_t b = std::size_t(rng.integer(0, int(s.parts.size()) - 1));
    p = s.transforms[b].apply(random_in(rng, s.parts[b]->support()));
  }
  return pts;
}

void require_same(const FieldSample& a, const FieldSample& b) {
  REQUIRE(a.value == b.value);
  REQUIRE(a.gradient == b.gradient);
}

}  // namespace

TEST_CASE("fixed16 grids agree with float32 grids within the stated bound", "[implicit][grid][compact]") {
  test::Rng rng(71);
  for (const auto& part : rig_like_parts())
    for (const int res : {8, 32, 64}) {
      const GridField f32(*part, Box3f{}, storage_options(res, GridStorage::float32));
      const GridField f16(*part, Box3f{}, storage_options(res, GridStorage::fixed16));
      REQUIRE(f16.storage() == GridStorage::fixed16);
      REQUIRE(f32.quantisation_bound()[0] == 0.f);
      const auto bound = f16.quantisation_bound();
      // Values in [0, 1]: about 1.5e-5; gradients: half a step of their largest component.
      CHECK(bound[0] < 2e-5f);
      double worst_value = 0, worst_gradient = 0;
      for (int i = 0; i < 20000; ++i) {
        const Vec3f p = random_in(rng, f32.support());
        const FieldSample a = f32.eval(p), b = f16.eval(p);
        worst_value = std::max(worst_value, double(std::fabs(a.value - b.value)));
        for (int c = 0; c < 3; ++c)
          worst_gradient = std::max(worst_gradient, double(std::fabs(a.gradient[c] - b.gradient[c])));
      }
      INFO("resolution " << res << ": value " << worst_value << " (bound " << bound[0] << "), gradient "
                         << worst_gradient << " (bound " << bound[1] << ")");
      CHECK(worst_value <= bound[0]);
      CHECK(worst_gradient <= bound[1]);
      CHECK(worst_value > 0);  // the quantisation is there (the test can fail)
      CHECK(f16.view().node_bytes() * 2 == f32.view().node_bytes());
    }
}

TEST_CASE("fixed16 grids: gradients agree with finite differences of the sampled field",
          "[implicit][grid][compact]") {
  // The stored gradient is the source's, quantised: against central differences of the source,
  // the fixed16 grid is as close as the float32 grid, to within the quantisation bound.
  test::Rng rng(72);
  for (const auto& part : rig_like_parts()) {
    const GridField f32(*part, Box3f{}, storage_options(32, GridStorage::float32));
    const GridField f16(*part, Box3f{}, storage_options(32, GridStorage::fixed16));
    const float h = 1e-3f * norm(f32.support().size());
    double err32 = 0, err16 = 0;
    for (int i = 0; i < 5000; ++i) {
      const Vec3f p = random_in(rng, f32.support());
      Vec3f fd;
      for (int a = 0; a < 3; ++a) {
        Vec3f e{0, 0, 0};
        e[a] = h;
        fd[a] = (part->eval(p + e).value - part->eval(p - e).value) / (2 * h);
      }
      err32 = std::max(err32, double(norm(f32.eval(p).gradient - fd)));
      err16 = std::max(err16, double(norm(f16.eval(p).gradient - fd)));
    }
    INFO("float32 " << err32 << ", fixed16 " << err16);
    CHECK(err16 <= err32 + std::sqrt(3.0) * f16.quantisation_bound()[1]);
  }
}

TEST_CASE("a grid's empty bricks hold the value 0 exactly, in both storages", "[implicit][grid][compact]") {
  // What lets the sparse evaluator skip a leaf at a point: its cell's nodes all store 0.
  const CapsuleField cap({0, 0, 0}, {0, 0, 1}, 0.2f, 0.2f);
  const Box3f wide{{-1, -1, -1}, {1, 1, 2}};
  test::Rng rng(79);
  for (const GridStorage storage : {GridStorage::fixed16, GridStorage::float32})
    for (const int res : {2, 5, 24, 33}) {
      const GridField grid(cap, wide, storage_options(res, storage));
      const GridView v = grid.view();
      REQUIRE(v.occupied != nullptr);
      int empty = 0, nonzero = 0;
      for (int i = 0; i < 20000; ++i) {
        const Vec3f p = random_in(rng, wide);
        const FieldSample s = eval_grid_inside(v, p);
        nonzero += s.value != 0.f;
        // The evaluator's fused test-and-interpolate agrees with both.
        FieldSample fused;
        const bool occupied = eval_grid_inside_occupied(v, p, fused);
        REQUIRE(occupied == grid_cell_occupied(v, p));
        if (occupied) require_same(fused, s);
        if (occupied) continue;
        ++empty;
        REQUIRE(s.value == 0.f);
      }
      INFO("resolution " << res);
      if (res >= 24) CHECK(empty > 5000);  // most of the wide box is far from the capsule
      if (res >= 5) CHECK(nonzero > 0);    // (at 2³ every node lies far from it)
    }
}

TEST_CASE("fixed16 grids are exactly 0 where the sampled field is and outside their box",
          "[implicit][grid][compact]") {
  const CapsuleField cap({0, 0, 0}, {0, 0, 1}, 0.2f, 0.2f);
  const Box3f wide{{-1, -1, -1}, {1, 1, 2}};  // far larger than the support: zero nodes around
  const GridField f16(cap, wide, storage_options(24, GridStorage::fixed16));
  test::Rng rng(73);
  int zeros = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3f p = random_in(rng, Box3f{{-1.5f, -1.5f, -1.5f}, {1.5f, 1.5f, 2.5f}});
    const FieldSample s = f16.eval(p);
    // Two cells beyond the support every node of the cell is 0.
    const bool far =
        !Box3f{cap.support().lo - Vec3f{0.2f, 0.2f, 0.3f}, cap.support().hi + Vec3f{0.2f, 0.2f, 0.3f}}
             .contains(p);
    if (!far) continue;
    ++zeros;
    REQUIRE(s.value == 0.f);
    REQUIRE(s.gradient == Vec3f{});
  }
  CHECK(zeros > 1000);
}

TEST_CASE("vectorised and scalar grid interpolation agree bit for bit in both storages, on faces and corners",
          "[implicit][grid][compact]") {
  test::Rng rng(74);
  const CapsuleField cap({0, 0, 0}, {0.2f, 0.1f, 0.7f}, 0.25f);
  for (const GridStorage storage : {GridStorage::fixed16, GridStorage::float32})
    for (const int res : {2, 3, 12, 32}) {
      const GridField grid(cap, Box3f{}, storage_options(res, storage));
      const GridView v = grid.view();
      REQUIRE((v.packed != nullptr) == (storage == GridStorage::fixed16));
      for (int i = 0; i < 20000; ++i) {
        Vec3f p;
        for (int a = 0; a < 3; ++a) {
          const int pick = rng.integer(0, 5);
          p[a] = pick == 0   ? v.box.lo[a]
                 : pick == 1 ? v.box.hi[a]
                             : float(rng.uniform(v.box.lo[a], v.box.hi[a]));
        }
        require_same(eval_grid_inside(v, p), eval_grid_inside_scalar(v, p));
      }
    }
}

TEST_CASE("a fixed16 grid decodes its nodes and copies keep their own", "[implicit][grid][compact]") {
  const SphereField sphere({0, 0, 0}, 1.f);
  const GridField f32(sphere, Box3f{}, storage_options(10, GridStorage::float32));
  const GridField f16(sphere, Box3f{}, storage_options(10, GridStorage::fixed16));
  const std::vector<float> a = f32.nodes(), b = f16.nodes();
  REQUIRE(a.size() == b.size());
  const auto bound = f16.quantisation_bound();
  for (std::size_t i = 0; i < a.size(); ++i) REQUIRE(std::fabs(a[i] - b[i]) <= bound[i % 4 == 0 ? 0 : 1]);
  // From node data (the distance fit's and Python's path), in either storage.
  const GridField again(10, f32.support(), a, GridStorage::fixed16);
  CHECK(again.nodes() == b);
  auto copy = std::make_unique<GridField>(f16);
  const Vec3f p{0.1f, 0.2f, -0.3f};
  const FieldSample before = f16.eval(p);
  CHECK(copy->view().packed != f16.view().packed);
  require_same(copy->eval(p), before);
}

TEST_CASE("batches culled per block, with repeated leaves and max bounds, equal the instruction loop",
          "[implicit][batch][compact]") {
  test::Rng rng(75);
  for (int round = 0; round < 6; ++round) {
    const SkeletonParts s = random_skeleton(rng, 6 + 10 * round, round % 2 == 0);
    std::vector<JointSetup> joints(s.parts.size());
    for (std::size_t j = 0; j < joints.size(); j += 2)
      joints[j].op =
          NodeOperator::grid_operator(sampled_blend_grid(), operators::Controller::preset("blend2013"), "g");
    const ProgramField field(build_tree_2013(s, joints));
    REQUIRE(field.program().sparse());
    std::vector<Vec3f> pts = points_near(rng, s, 3001);
    pts[17] = Vec3f{NAN, 0.f, 0.f};  // a NaN point does not disturb its block
    // The reference: the instruction loop (every node composed, no sharing; its pruning by
    // world boxes changes no result, and keeps the NaN point out of every leaf).
    ScalarEvaluator loop(field.program(), field.pose());
    std::vector<FieldSample> ref(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) ref[i] = loop.eval(pts[i], nullptr, true);
    const SparseEvaluator one(field.program(), field.pose());
    for (const bool cull : {false, true}) {
      BatchEvaluator batch(field.program(), field.pose(), BatchOptions{cull});
      std::vector<FieldSample> out(pts.size());
      batch.eval(pts.data(), pts.size(), out.data());
      std::vector<float> values(pts.size());
      std::vector<Vec3f> gradients(pts.size());
      batch.eval(pts.data(), pts.size(), values.data(), gradients.data());
      for (std::size_t i = 0; i < pts.size(); ++i) {
        INFO("round " << round << ", cull " << cull << ", point " << i);
        require_same(out[i], ref[i]);
        require_same(FieldSample{values[i], gradients[i]}, ref[i]);
        if (!cull) require_same(one.eval(pts[i]), ref[i]);
      }
    }
  }
}

TEST_CASE("repeated leaves are evaluated once, and a copy moved on its own is not shared",
          "[implicit][tree][compact]") {
  test::Rng rng(76);
  const SkeletonParts s = random_skeleton(rng, 12, true);
  const CompositionTree tree = build_tree_2013(s, std::vector<JointSetup>(s.parts.size()));
  const auto program = std::make_shared<const Program>(tree);
  auto pose = std::make_shared<Pose>(*program);
  const std::size_t L = program->leaves().size();
  REQUIRE(L == 2 * (s.parts.size() - 1));
  auto distinct = [](const Pose& p) {
    return __builtin_popcountll(p.distinct_leaves()[0]) + __builtin_popcountll(p.distinct_leaves()[1]);
  };
  // A bone appears once per pair it is in; each is evaluated once.
  CHECK(std::size_t(distinct(*pose)) == s.parts.size());
  // Move one copy of a repeated bone alone: it becomes distinct, and every result still equals
  // the evaluation without sharing (the instruction loop).
  std::size_t moved = L;
  for (std::size_t k = 1; k < L && moved == L; ++k)
    for (std::size_t j = 0; j < k; ++j)
      if (&program->field(std::size_t(program->leaves()[j].field)) ==
          &program->field(std::size_t(program->leaves()[k].field)))
        moved = k;
  REQUIRE(moved < L);
  Rigid3f x = pose->leaves()[moved].local_to_world;
  x.t = x.t + Vec3f{0.05f, 0.f, 0.f};
  pose->set_leaf_transform(*program, moved, x);
  CHECK(std::size_t(distinct(*pose)) == s.parts.size() + 1);
  const ProgramField field(program, pose);
  ScalarEvaluator loop(*program, *pose);
  const std::vector<Vec3f> pts = points_near(rng, s, 4000);
  std::vector<FieldSample> out(pts.size());
  field.eval_batch(pts.data(), pts.size(), out.data(), 0);
  int nonzero = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const FieldSample ref = loop.eval(pts[i], nullptr, false);
    nonzero += ref.value != 0.f;
    require_same(out[i], ref);
    require_same(field.eval(pts[i]), ref);
  }
  CHECK(nonzero > 3000);
}

TEST_CASE("a program's memory: fixed16 leaves take half of float32's, fixed16 operators half",
          "[implicit][compact]") {
  auto make = [](GridStorage storage) {
    const auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.2f);
    const auto grid = std::make_shared<const GridField>(*cap, Box3f{}, storage_options(20, storage));
    Rigid3f x;
    x.t = Vec3f{0.3f, 0, 0};
    // The same grid twice counts once.
    return Program(CompositionTree::node(NodeOperator::max(), CompositionTree::leaf(grid),
                                         CompositionTree::leaf(grid, x)));
  };
  const std::size_t f32 = make(GridStorage::float32).memory_bytes(),
                    f16 = make(GridStorage::fixed16).memory_bytes();
  // 20³ nodes, and 5³ occupancy bricks in two 64-bit words.
  CHECK(f32 == 20u * 20u * 20u * 16u + 16u);
  CHECK(f16 == 20u * 20u * 20u * 8u + 16u);
  // A grid operator counts its padded copy (4 or 2 bytes a sample) and its bound table; the
  // program keeps no reference to the tree's operator.
  const auto op = sampled_blend_grid();
  const long uses = op.use_count();
  const auto tree =
      CompositionTree::node(NodeOperator::grid_operator(op, operators::Controller::preset("contact"), "g"),
                            CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{0, 0, 0}, 1.f)),
                            CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{1, 0, 0}, 1.f)));
  const long tree_uses = op.use_count();
  const Program op32(tree), op16(tree, ProgramOptions{GridStorage::fixed16});  // float32: the default
  CHECK(op.use_count() == tree_uses);
  CHECK(tree_uses > uses);
  CHECK(op32.memory_bytes() == (5u * 35u * 35u + 32u * 32u) * sizeof(float));
  // 35 padded nodes a row: 5 × 5 tiles of 8 × 8 a slice, two floats each.
  CHECK(op16.memory_bytes() ==
        5u * 35u * 35u * sizeof(std::int16_t) + (5u * 5u * 5u * 2u + 32u * 32u) * sizeof(float));
  CHECK(op32.grids()[0].data == nullptr);
  CHECK(op16.grids()[0].padded == nullptr);
}

TEST_CASE("fixed16 grid operators agree with the float operator within the stated bound",
          "[implicit][tree][compact]") {
  // docs/implicit.md, "Operator storage": value within 1.5625 s / 2, each partial derivative
  // within 1.25 × 3 × (nf − 1) × s / 2, s the largest tile step.
  const auto blend = sampled_blend_grid();
  const auto bumpy = std::make_shared<const operators::GridOperator>(operators::sample_operator(
      [](float f1, float f2, float d) {
        return std::max(f1, f2) + 0.3f * d * std::sin(9.f * f1) * std::sin(7.f * f2) * f1 * f2;
      },
      17, 4));
  // The skinning pipeline's 2013 blend at the paper's 128 × 128² (the operator it stores fixed16).
  const auto blend128 =
      std::make_shared<const operators::GridOperator>(operators::sampled_gradient_blend_2013(128, 128));
  test::Rng rng(79);
  for (const auto& op : {blend, bumpy, blend128}) {
    const auto tree = CompositionTree::node(
        NodeOperator::grid_operator(op, operators::Controller::preset("contact"), "g"),
        CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{0, 0, 0}, 1.f)),
        CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{0.8f, 0, 0}, 1.f)));
    const Program p32(tree), p16(tree, ProgramOptions{GridStorage::fixed16});
    const operators::GridOperatorView &g32 = p32.grids()[0], &g16 = p16.grids()[0];
    REQUIRE(g16.packed != nullptr);
    float step = 0.f;  // the largest tile step
    for (std::size_t t = 0; t < g16.packed_tile_count(); ++t)
      step = std::max(step, g16.packed_tiles[2 * t + 1]);
    float largest = 0.f;
    for (float v : op->data()) largest = std::max(largest, std::fabs(v));
    INFO("largest tile step " << step << ", largest sample " << largest);
    CHECK(step < largest / 65534.f);  // the tiles are finer than one scale for the grid
    // A few per cent above the bound's float for the float rounding of the kernel.
    const float value_bound = 1.5625f * step / 2.f * 1.01f + 1e-6f,
                slope_bound = 1.25f * 3.f * float(op->nf() - 1) * step / 2.f * 1.01f + 1e-5f;
    float worst_value = 0.f, worst_slope = 0.f;
    for (int i = 0; i < 50000; ++i) {
      // Half the points on cell edges and grid borders, where the ghost nodes are read.
      float f[3];
      for (float& x : f) {
        x = float(rng.uniform(-0.05, 1.05));
        if (rng.integer(0, 1) == 0) x = std::round(x * float(op->nf() - 1)) / float(op->nf() - 1);
      }
      const operators::OpSample a = g32.eval(f[0], f[1], f[2]), b = g16.eval(f[0], f[1], f[2]);
      REQUIRE(a.g == op->eval(f[0], f[1], f[2]).g);  // float32: the operator bit for bit
      worst_value = std::max(worst_value, std::fabs(a.g - b.g));
      worst_slope = std::max({worst_slope, std::fabs(a.dg1 - b.dg1), std::fabs(a.dg2 - b.dg2)});
    }
    CHECK(worst_value <= value_bound);
    CHECK(worst_slope <= slope_bound);
    CHECK(worst_value > 0.f);  // the two storages are not the same array
    // The composed field: its value moves by no more than the operator's.
    const Pose pose32(p32), pose16(p16);
    ScalarEvaluator e32(p32, pose32), e16(p16, pose16);
    for (int i = 0; i < 2000; ++i) {
      const Vec3f x = test::to_float(rng.vec(-1.2, 2.0));
      CHECK(std::fabs(e32.eval(x, nullptr, true).value - e16.eval(x, nullptr, true).value) <= value_bound);
    }
  }
}

TEST_CASE("a grid operator's bound table bounds it in every cell, whatever d", "[implicit][tree][compact]") {
  // What lets the sparse evaluator skip the operands of a max that cannot win.
  const auto blend = sampled_blend_grid();
  const auto bumpy = std::make_shared<const operators::GridOperator>(operators::sample_operator(
      [](float f1, float f2, float d) {
        return std::max(f1, f2) + 0.3f * d * std::sin(9.f * f1) * std::sin(7.f * f2) * f1 * f2;
      },
      17, 4));
  test::Rng rng(78);
  for (const auto& [op, storage] :
       {std::pair{blend, GridStorage::fixed16}, std::pair{bumpy, GridStorage::fixed16},
        std::pair{blend, GridStorage::float32}, std::pair{bumpy, GridStorage::float32}}) {
    const Program p(CompositionTree::node(
                        NodeOperator::grid_operator(op, operators::Controller::preset("contact"), "g"),
                        CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{0, 0, 0}, 1.f)),
                        CompositionTree::leaf(std::make_shared<const SphereField>(Vec3f{1, 0, 0}, 1.f))),
                    ProgramOptions{storage});
    const operators::GridOperatorView& g = p.grids()[0];
    const float* table = p.grid_bounds()[0];
    REQUIRE(table != nullptr);
    float tightest = INFINITY;
    for (int i = 0; i < 100000; ++i) {
      const float f1 = float(rng.uniform(0, 1)), f2 = float(rng.uniform(0, 1)), d = float(rng.uniform(0, 1));
      int i1 = 0, i2 = 0;
      float t = 0;
      g.locate(f1, i1, t);
      g.locate(f2, i2, t);
      const float bound = table[std::size_t(i1) * std::size_t(g.nf - 1) + std::size_t(i2)];
      const float v = g.eval(f1, f2, d).g;
      REQUIRE(v <= bound);
      tightest = std::min(tightest, bound - v);
    }
    CHECK(tightest < 0.1f);  // a bound, not a blanket
  }
}
