// SPDX-License-Identifier: MIT
// Composition tree, program, pose and evaluators: every evaluator = recursive evaluation, pruning
// changes nothing, gradients against finite differences (constant-d operators), rigid leaf
// updates through poses, diagnostics, batch agreement, and the 2013 / 2014 builders and their
// node tags.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <set>
#include <vector>

#include "implicit/tree_fixtures.h"
#include "isokit/core/error.h"
#include "isokit/implicit/evaluators.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "isokit/implicit/program_field.h"
#include "isokit/implicit/skeleton.h"
#include "isokit/operators/analytic.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;
using isokit::test::random_op;
using isokit::test::random_rigid;
using isokit::test::random_tree;
using isokit::test::sampled_blend_grid;
namespace ops = isokit::operators;

TEST_CASE("program evaluation equals recursive evaluation, pruning changes no result", "[tree]") {
  test::Rng rng(31);
  for (int trial = 0; trial < 8; ++trial) {
    const CompositionTree tree = random_tree(rng, rng.integer(1, 24), false);
    const ProgramField field(
        tree, ProgramOptions{GridStorage::float32});  // (the default) the tree's operators bit for bit
    const Program& program = field.program();
    ScalarEvaluator scalar(program, field.pose());
    CHECK(program.size() == tree.node_count());
    std::vector<NodeDiagnostics> diag(program.size());
    int pruned = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3f p = test::to_float(rng.vec(-3.5, 3.5));
      const FieldSample ref = tree.eval_recursive(p);
      const FieldSample fast = field.eval(p);
      const FieldSample full = scalar.eval(p, nullptr, false);
      const FieldSample withdiag = scalar.eval(p, diag.data(), true);
      INFO("value " << fast.value << " vs " << ref.value << ", gradient " << fast.gradient.x << " "
                    << fast.gradient.y << " " << fast.gradient.z << " vs " << ref.gradient.x << " "
                    << ref.gradient.y << " " << ref.gradient.z);
      REQUIRE(fast.value == ref.value);
      REQUIRE(fast.gradient == ref.gradient);
      REQUIRE(full.value == ref.value);
      REQUIRE(full.gradient == ref.gradient);
      REQUIRE(withdiag.value == ref.value);
      for (const auto& d : diag) pruned += d.evaluated ? 0 : 1;
      if (!field.support().contains(p)) CHECK(fast.value == 0.f);
    }
    if (trial > 0) CHECK(pruned > 0);  // pruning did happen
  }
}

TEST_CASE("tree gradients agree with central differences (constant-d operators)", "[tree]") {
  test::Rng rng(32);
  int tested = 0;
  double worst = 0;
  for (int trial = 0; trial < 4; ++trial) {
    // Analytic leaves: a grid's gradient is its interpolated stored gradient, not the derivative
    // of its trilinear value (see the grid tests).
    const ProgramField field(random_tree(rng, 10, true, 0));
    for (int i = 0; i < 2000; ++i) {
      const Vec3d p = rng.vec(-3, 3);
      const auto f = [&](const Vec3d& q) { return double(field.eval(test::to_float(q)).value); };
      const Vec3d fd = test::central_gradient(f, p, 2e-3);
      const Vec3d fd2 = test::central_gradient(f, p, 1e-3);
      // Skip points within a step of a kink (max ties, clamps): there the two steps disagree.
      if (norm(fd - fd2) > 0.02 * std::max(1.0, norm(fd))) continue;
      ++tested;
      const Vec3d g = test::to_double(field.eval(test::to_float(p)).gradient);
      worst = std::max(worst, norm(g - fd) / std::max(1.0, norm(fd)));
    }
  }
  INFO("points tested: " << tested << ", worst relative error " << worst);
  CHECK(tested > 6000);
  CHECK(worst <= 0.03);
}

TEST_CASE("posing leaf transforms moves the field rigidly", "[tree]") {
  test::Rng rng(33);
  const CompositionTree tree = random_tree(rng, 12, false);
  const auto program = std::make_shared<const Program>(tree, ProgramOptions{GridStorage::float32});
  const ProgramField before(program, std::make_shared<const Pose>(*program));
  auto moved_pose = std::make_shared<Pose>(*program);
  const Rigid3f T = random_rigid(rng, 2.0);
  for (std::size_t l = 0; l < program->leaves().size(); ++l)
    moved_pose->set_leaf_transform(*program, l, T * program->leaves()[l].local_to_world);
  const ProgramField field = before.with_pose(moved_pose);
  double worst_v = 0, worst_g = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3f p = test::to_float(rng.vec(-3, 3));
    const FieldSample a = before.eval(p);
    const FieldSample b = field.eval(T.apply(p));
    worst_v = std::max(worst_v, double(std::abs(a.value - b.value)));
    worst_g = std::max(worst_g, double(norm(T.rotate(a.gradient) - b.gradient)));
  }
  CHECK(worst_v <= 1e-4);
  CHECK(worst_g <= 1e-3);

  // Moving one leaf equals rebuilding the tree with that leaf moved.
  auto one_pose = std::make_shared<Pose>(*program);
  const Rigid3f M = random_rigid(rng, 0.5);
  one_pose->set_transform_of(*program, 3, M);
  const ProgramField one = before.with_pose(one_pose);
  std::function<CompositionTree(const CompositionTree&)> moved = [&](const CompositionTree& t) {
    if (t.is_leaf()) return t.id() == 3 ? CompositionTree::leaf(t.field(), M, 3) : t;
    return CompositionTree::node(t.op(), moved(t.first()), moved(t.second()));
  };
  const CompositionTree rebuilt = moved(tree);
  for (int i = 0; i < 1000; ++i) {
    const Vec3f p = test::to_float(rng.vec(-3, 3));
    REQUIRE(one.eval(p).value == rebuilt.eval_recursive(p).value);
  }
  CHECK_THROWS_AS(one_pose->set_transform_of(*program, 99, M), InputError);
  CHECK_THROWS_AS(one_pose->set_leaf_transform(*program, 999, M), InputError);
  // A pose belongs to its program.
  const Program other(random_tree(rng, 5, false));
  CHECK_THROWS_WITH(one_pose->set_transform_of(other, 3, M), Catch::Contains("another program"));
  CHECK_THROWS_WITH(ScalarEvaluator(other, *one_pose), Catch::Contains("another program"));
  CHECK_THROWS_WITH(ProgramField(std::make_shared<const Program>(other), one_pose),
                    Catch::Contains("another program"));
}

TEST_CASE("scalar evaluator diagnostics report alpha, d, the dominant operand and contact", "[tree]") {
  auto a = std::make_shared<const SphereField>(Vec3f{-0.3f, 0, 0}, 0.5f);
  auto b = std::make_shared<const SphereField>(Vec3f{0.3f, 0, 0}, 0.5f);
  const auto grid = sampled_blend_grid();
  const Program program(
      CompositionTree::node(NodeOperator::grid_operator(grid, ops::Controller::preset("contact"), "g"),
                            CompositionTree::leaf(a), CompositionTree::leaf(b)));
  const Pose pose(program);
  ScalarEvaluator scalar(program, pose);
  std::vector<NodeDiagnostics> diag(program.size());
  // On the x axis between the centres the gradients are opposite: α = π, d = 1, both inside.
  scalar.eval({0.05f, 0, 0}, diag.data(), true);
  CHECK(diag[2].alpha == Approx(kPi).margin(1e-3));
  CHECK(diag[2].d == Approx(1.0).margin(1e-3));
  CHECK(diag[2].on_contact == 1);
  CHECK(diag[2].dominant == 2);  // closer to b's centre
  // Far from b: a dominates, no contact.
  scalar.eval({-0.8f, 0.1f, 0}, diag.data(), true);
  CHECK(diag[2].dominant == 1);
  CHECK(diag[2].on_contact == 0);
  CHECK(diag[1].evaluated == 0);  // b's leaf pruned
  // Batch evaluation: every grain gives the same bits.
  test::Rng rng(34);
  const ProgramField big(random_tree(rng, 20, false));
  std::vector<Vec3f> pts(20000);
  for (auto& p : pts) p = test::to_float(rng.vec(-3, 3));
  std::vector<FieldSample> s0(pts.size()), s1(pts.size());
  big.eval_batch(pts.data(), pts.size(), s0.data(), 0);
  big.eval_batch(pts.data(), pts.size(), s1.data(), 97);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    REQUIRE(s0[i].value == s1[i].value);
    REQUIRE(s0[i].gradient == s1[i].gradient);
  }
}

TEST_CASE("a node's controller table can be replaced in place", "[tree]") {
  auto a = std::make_shared<const SphereField>(Vec3f{-0.3f, 0, 0}, 0.5f);
  auto b = std::make_shared<const SphereField>(Vec3f{0.3f, 0, 0}, 0.5f);
  const auto grid = sampled_blend_grid();
  auto tree_with = [&](const char* preset) {
    return CompositionTree::node(NodeOperator::grid_operator(grid, ops::Controller::preset(preset), "g"),
                                 CompositionTree::leaf(a), CompositionTree::leaf(b));
  };
  const auto program = std::make_shared<const Program>(tree_with("contact"));
  Pose pose(*program);
  const ProgramField zero(tree_with("constant0"));
  CHECK(pose.controller(*program, 2).values[255] == Approx(1.f));
  // The contact controller replaced by d ≡ 0: the same field as a program built with it, through
  // the sparse evaluator and the instruction loop; the program keeps the tree's table.
  pose.set_controller(*program, 2, ops::Controller::preset("constant0").table());
  CHECK(pose.controller(*program, 2).values[255] == 0.f);
  CHECK(program->controller(2).values[255] == Approx(1.f));
  const ProgramField field(program, std::make_shared<const Pose>(pose));
  ScalarEvaluator scalar(*program, field.pose());
  test::Rng rng(35);
  std::vector<NodeDiagnostics> diag(program->size());
  for (int k = 0; k < 200; ++k) {
    const Vec3f p = test::to_float(rng.vec(-1, 1));
    const FieldSample s = field.eval(p), r = zero.eval(p);
    REQUIRE(s.value == r.value);
    REQUIRE(s.gradient == r.gradient);
    REQUIRE(scalar.eval(p, diag.data(), false).value == r.value);
  }
  CHECK_THROWS_WITH(pose.set_controller(*program, 0, ops::ControllerTable{}),
                    Catch::Contains("not an inner node"));
  CHECK_THROWS_WITH(pose.controller(*program, 3), Catch::Contains("program instruction 3"));
  CHECK_THROWS_WITH(program->controller(3), Catch::Contains("program instruction 3"));
  ops::ControllerTable bad{};
  bad.values[7] = std::nanf("");
  CHECK_THROWS_WITH(pose.set_controller(*program, 2, bad), Catch::Contains("outside [0, 1]"));
  bad.values[7] = 1.5f;
  CHECK_THROWS_WITH(pose.set_controller(*program, 2, bad), Catch::Contains("outside [0, 1]"));
}

TEST_CASE("deep trees use a heap value stack with the same results", "[tree]") {
  // Right-deep chain: the value stack holds one entry per leaf (more than the 64 local slots).
  test::Rng rng(36);
  auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 0.5f}, 0.2f);
  CompositionTree t = CompositionTree::leaf(cap, random_rigid(rng, 1.0), 0);
  for (int i = 1; i < 100; ++i)
    t = CompositionTree::node(NodeOperator::clean_union(),
                              CompositionTree::leaf(cap, random_rigid(rng, 1.0), i), t);
  const ProgramField field(t);
  CHECK(field.program().max_stack() == 100);
  for (int i = 0; i < 500; ++i) {
    const Vec3f p = test::to_float(rng.vec(-1.5, 1.5));
    const FieldSample a = field.eval(p), b = t.eval_recursive(p);
    REQUIRE(a.value == b.value);
    REQUIRE(a.gradient == b.gradient);
  }
}

TEST_CASE("sparse evaluation equals the reference up to 127 leaves and beyond", "[tree][slow]") {
  // Trees of up to 127 leaves take the sparse path (leaf boxes tested at once, only nodes with two
  // non-zero operands composed; the leaf mask's two words meet at 64); larger trees the
  // instruction loop. Both equal the recursive reference and the instruction loop with pruning
  // bit for bit, point by point and in batches.
  test::Rng rng(37);
  for (const int n : {2, 5, 62, 63, 64, 65, 100, 127, 128}) {
    const CompositionTree tree = random_tree(rng, n, false);
    const ProgramField field(
        tree, ProgramOptions{GridStorage::float32});  // (the default) the tree's operators bit for bit
    ScalarEvaluator scalar(field.program(), field.pose());
    CHECK(field.program().sparse() == (n <= 127));
    std::vector<Vec3f> pts(4001);
    for (auto& p : pts) p = test::to_float(rng.vec(-3.5, 3.5));
    std::vector<FieldSample> batch(pts.size()), serial(pts.size());
    field.eval_batch(pts.data(), pts.size(), batch.data(), 0);
    field.eval_batch(pts.data(), pts.size(), serial.data(), 7);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const FieldSample ref = tree.eval_recursive(pts[i]);
      const FieldSample loop = scalar.eval(pts[i], nullptr, true);
      const FieldSample fast = field.eval(pts[i]);
      INFO(n << " leaves, point " << i);
      REQUIRE(fast.value == ref.value);
      REQUIRE(fast.gradient == ref.gradient);
      REQUIRE(loop.value == ref.value);
      REQUIRE(loop.gradient == ref.gradient);
      REQUIRE(batch[i].value == ref.value);
      REQUIRE(batch[i].gradient == ref.gradient);
      REQUIRE(serial[i].value == ref.value);
      REQUIRE(serial[i].gradient == ref.gradient);
    }
  }
}

TEST_CASE("a sparse layout (the CUDA tape's) holds up to 63 leaves, the host evaluator more", "[tree]") {
  test::Rng rng(41);
  for (const int n : {63, 64}) {
    const ProgramField field(random_tree(rng, n, false));
    REQUIRE(field.program().sparse());
    if (n <= 63) {
      CHECK(sparse_layout(field.program(), field.pose()).leaves == std::size_t(n));
    } else {
      CHECK_THROWS_WITH(sparse_layout(field.program(), field.pose()),
                        Catch::Contains("64)") && Catch::Contains("between 2 and 63"));
    }
  }
}

TEST_CASE("sparse evaluation on the faces of grid leaves' boxes", "[tree]") {
  // Grid leaves placed by the identity and by quarter turns (exact in float): points exactly on
  // a box face, edge or corner are inside (the sparse path must test the box as eval_grid does).
  const auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 0.5f}, 0.3f);
  const auto grid = std::make_shared<const GridField>(*cap, Box3f{}, GridFieldOptions{9, 0});
  Rigid3f turn;
  turn.R.m[0] = 0, turn.R.m[1] = -1, turn.R.m[3] = 1, turn.R.m[4] = 0;  // 90° about z
  turn.t = Vec3f{0.25f, 0.f, 0.125f};
  const CompositionTree tree = CompositionTree::node(
      NodeOperator::grid_operator(sampled_blend_grid(), ops::Controller::preset("contact"), "g"),
      CompositionTree::leaf(grid), CompositionTree::leaf(grid, turn));
  const ProgramField field(
      tree, ProgramOptions{GridStorage::float32});  // (the default) the tree's operators bit for bit
  const Box3f b = grid->support();
  test::Rng rng(38);
  int on_face = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3f p = test::to_float(rng.vec(-1, 1));
    for (int a = 0; a < 3; ++a) {
      const int pick = rng.integer(0, 3);  // lo, hi, or leave
      if (pick < 2) p[a] = pick == 0 ? b.lo[a] : b.hi[a];
    }
    if (rng.integer(0, 1)) p = turn.apply(p);  // on the second leaf's faces
    const FieldSample ref = tree.eval_recursive(p), fast = field.eval(p);
    on_face += ref.value != 0.f;
    REQUIRE(fast.value == ref.value);
    REQUIRE(fast.gradient == ref.gradient);
  }
  CHECK(on_face > 100);
}

TEST_CASE("the host/device layout evaluator equals the sparse evaluator bit for bit", "[tree]") {
  // eval_sparse_layout is what the CUDA kernel runs per thread; on the host it must give the
  // sparse evaluator's own (vectorised) results exactly, for trees of grid leaves and every
  // operator kind, and again at another pose.
  test::Rng rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const Program program(random_tree(rng, rng.integer(2, 40), false, 1));
    REQUIRE(program.sparse());
    Pose pose(program);
    for (int moved = 0; moved < 2; ++moved) {
      const TapeSparseLayout layout = sparse_layout(program, pose);
      const SparseEvaluator sparse(program, pose);
      int nonzero = 0;
      for (int k = 0; k < 3000; ++k) {
        const Vec3f p = test::to_float(rng.vec(-2.0, 2.0));
        const FieldSample a = sparse.eval(p), b = eval_sparse_layout(layout, p);
        REQUIRE(a.value == b.value);
        REQUIRE(a.gradient == b.gradient);
        nonzero += a.value != 0.f;
      }
      CHECK(nonzero > 300);
      for (std::size_t k = 0; k < program.leaves().size(); ++k)
        pose.set_leaf_transform(program, k, random_rigid(rng, 1.0));
    }
  }
  const auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.3f);
  const Program single(CompositionTree::leaf(cap, Rigid3f{}, 0));
  const Pose single_pose(single);
  CHECK_THROWS_WITH(sparse_layout(single, single_pose), Catch::Contains("has no sparse layout"));
  CHECK_THROWS_WITH(SparseEvaluator(single, single_pose), Catch::Contains("not evaluated sparsely"));
}

TEST_CASE("a copied program outlives the original", "[tree]") {
  test::Rng rng(40);
  const CompositionTree tree = random_tree(rng, 12, false);
  auto original = std::make_unique<Program>(tree);
  const Program copy = *original;
  const Pose pose(*original);
  original.reset();  // the copy shares the padded grid operators
  BatchEvaluator batch(copy, pose);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f p = test::to_float(rng.vec(-3, 3));
    FieldSample s;
    batch.eval(&p, 1, &s);
    REQUIRE(s.value == tree.eval_recursive(p).value);
  }
}

TEST_CASE("one program, two poses: evaluators of both at once", "[tree]") {
  // The same program read at two poses by batch evaluators on several threads: each pose gives
  // what a program compiled from the tree moved to that pose gives.
  test::Rng rng(41);
  const CompositionTree tree = random_tree(rng, 16, false);
  const auto program = std::make_shared<const Program>(tree);
  auto moved = std::make_shared<Pose>(*program);
  const Rigid3f T = random_rigid(rng, 1.0);
  for (std::size_t l = 0; l < program->leaves().size(); ++l)
    moved->set_leaf_transform(*program, l, T * program->leaves()[l].local_to_world);
  const ProgramField rest(program, std::make_shared<const Pose>(*program)), posed = rest.with_pose(moved);
  std::vector<Vec3f> pts(20000);
  for (auto& p : pts) p = test::to_float(rng.vec(-3, 3));
  std::vector<FieldSample> a(pts.size()), b(pts.size());
  parallel_for(pts.size(), 512, [&](std::size_t begin, std::size_t end) {
    BatchEvaluator ea(*program, rest.pose()), eb(*program, posed.pose());
    ea.eval(pts.data() + begin, end - begin, a.data() + begin);
    eb.eval(pts.data() + begin, end - begin, b.data() + begin);
  });
  std::vector<float> values(pts.size());
  std::vector<Vec3f> gradients(pts.size());
  BatchEvaluator(*program, posed.pose()).eval(pts.data(), pts.size(), values.data(), gradients.data());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    REQUIRE(a[i].value == rest.eval(pts[i]).value);
    const FieldSample s = posed.eval(pts[i]);
    REQUIRE(b[i].value == s.value);
    REQUIRE(b[i].gradient == s.gradient);
    REQUIRE(values[i] == s.value);
    REQUIRE(gradients[i] == s.gradient);
  }
}

TEST_CASE("fast_acos agrees with std::acos", "[tree]") {
  double worst = 0;
  for (int i = 0; i <= 200000; ++i) {
    const float x = -1.f + 2.f * float(i) / 200000.f;
    worst = std::max(worst, std::abs(double(fast_acos(x)) - std::acos(double(x))));
  }
  CHECK(worst <= 2e-6);
}

TEST_CASE("grid operators must vanish at (0, 0)", "[tree]") {
  std::vector<float> data(2 * 4 * 4, 0.1f);
  auto bad = std::make_shared<const ops::GridOperator>(2, 4, data);
  CHECK_THROWS_WITH(NodeOperator::grid_operator(bad, ops::Controller::preset("contact"), "bad"),
                    Catch::Contains("bad") && Catch::Contains("compact support"));
  CHECK_THROWS_AS(CompositionTree::leaf(nullptr), InputError);
}

namespace {

/// Skeleton: 0 torso (root) - 1 upper arm - 2 forearm - 3 hand, and 0 - 4 head.
SkeletonParts arm_skeleton() {
  SkeletonParts s;
  s.parent = {-1, 0, 1, 2, 0};
  const Vec3f a[5] = {{0, 0, 0}, {0.2f, 0, 1}, {1.2f, 0, 1}, {2.2f, 0, 1}, {0, 0, 1.2f}};
  const Vec3f b[5] = {{0, 0, 1.2f}, {1.2f, 0, 1}, {2.2f, 0, 1}, {2.6f, 0, 1}, {0, 0, 1.6f}};
  for (int i = 0; i < 5; ++i) {
    s.parts.push_back(std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, b[i] - a[i], 0.2f));
    Rigid3f x;
    x.t = a[i];
    s.transforms.push_back(x);
  }
  return s;
}

void collect(const CompositionTree& t, std::vector<int>& ids, std::vector<std::string>& ops) {
  if (t.is_leaf()) {
    ids.push_back(t.id());
    return;
  }
  ops.push_back(t.op().name);
  collect(t.first(), ids, ops);
  collect(t.second(), ids, ops);
}

}  // namespace

TEST_CASE("2013 builder: neighbouring pairs by their joint operator, then max", "[tree][builder]") {
  const SkeletonParts s = arm_skeleton();
  std::vector<JointSetup> joints(5);
  joints[2].op = NodeOperator::gradient_blend(ops::Controller::preset("blend2013"));  // elbow
  const CompositionTree t = build_tree_2013(s, joints);
  std::vector<int> ids;
  std::vector<std::string> names;
  collect(t, ids, names);
  CHECK(ids.size() == 8);                                         // 4 joints, 2 leaves each
  CHECK(std::count(names.begin(), names.end(), "max") == 3 + 3);  // 3 max pairs + 3 top-level max
  CHECK(std::count_if(names.begin(), names.end(),
                      [](const std::string& n) { return n.rfind("gradient", 0) == 0; }) == 1);
  // The tree is the max over the pair fields.
  const ProgramField field(t);
  test::Rng rng(35);
  for (int i = 0; i < 500; ++i) {
    const Vec3f p = test::to_float(rng.vec(-0.5, 3));
    float expect = 0;
    for (int c = 1; c < 5; ++c) {
      const int pa = s.parent[std::size_t(c)];
      const CompositionTree pair = CompositionTree::node(
          joints[std::size_t(c)].op,
          CompositionTree::leaf(s.parts[std::size_t(pa)], s.transforms[std::size_t(pa)]),
          CompositionTree::leaf(s.parts[std::size_t(c)], s.transforms[std::size_t(c)]));
      const FieldSample g = pair.eval_recursive(p);
      expect = std::max(expect, g.value);
    }
    REQUIRE(field.eval(p).value == Approx(expect).margin(1e-6));
  }
}

TEST_CASE("2014 builder: bulge pairs at the bottom, contact nodes up to one root", "[tree][builder]") {
  const SkeletonParts s = arm_skeleton();
  const auto grid = sampled_blend_grid();
  const NodeOperator contact =
      NodeOperator::grid_operator(grid, ops::Controller::preset("contact"), "contact");
  const NodeOperator bulge = NodeOperator::grid_operator(grid, ops::Controller::preset("bulge"), "bulge");
  std::vector<JointSetup> joints(5, JointSetup{contact, false});
  joints[3] = JointSetup{bulge, true};  // wrist: hand with forearm as a bulge pair
  const CompositionTree t = build_tree_2014(s, joints);
  std::vector<int> ids;
  std::vector<std::string> names;
  collect(t, ids, names);
  CHECK(ids.size() == 5);
  CHECK(std::set<int>(ids.begin(), ids.end()).size() == 5);  // every bone exactly once
  CHECK(std::count(names.begin(), names.end(), "bulge") == 1);
  CHECK(std::count(names.begin(), names.end(), "contact") == 3);
  // The bulge pair sits at the bottom: its node has two leaves (forearm, hand).
  std::function<bool(const CompositionTree&)> has_bottom_bulge = [&](const CompositionTree& n) {
    if (n.is_leaf()) return false;
    if (n.op().name == "bulge")
      return n.first().is_leaf() && n.second().is_leaf() && n.first().id() == 2 && n.second().id() == 3;
    return has_bottom_bulge(n.first()) || has_bottom_bulge(n.second());
  };
  CHECK(has_bottom_bulge(t));
  // Non-neighbouring parts (hand 3 and head 4) meet through a contact node: the root.
  CHECK(t.op().name == "contact");
  // Bad skeletons are refused by name.
  SkeletonParts two_roots = s;
  two_roots.parent[4] = -1;
  CHECK_THROWS_WITH(build_tree_2014(two_roots, joints), Catch::Contains("second root"));
  SkeletonParts cycle = s;
  cycle.parent = {-1, 2, 1, 2, 0};
  CHECK_THROWS_WITH(build_tree_2013(cycle, joints), Catch::Contains("not one tree"));
  CHECK_THROWS_AS(build_tree_2013(s, std::vector<JointSetup>(3)), InputError);
}

namespace {

/// The bone ids under `t`, checking on the way that every inner node's tag names a skeleton
/// edge with the child on one side and its parent on the other (or no joint: a 2013 max node).
std::set<int> check_tags(const CompositionTree& t, const SkeletonParts& s,
                         const std::vector<JointSetup>& joints, std::vector<NodeTag>& post_order) {
  if (t.is_leaf()) {
    post_order.push_back(NodeTag{});
    return {t.id()};
  }
  const std::set<int> a = check_tags(t.first(), s, joints, post_order);
  const std::set<int> b = check_tags(t.second(), s, joints, post_order);
  const NodeTag& tag = t.tag();
  post_order.push_back(tag);
  if (tag.joint < 0) {
    CHECK(t.op().kind == OpKind::Max);
    CHECK(tag.role == NodeRole::None);
  } else {
    CHECK(s.parent[std::size_t(tag.joint)] == tag.parent);
    CHECK(tag.role == joints[std::size_t(tag.joint)].role);
    CHECK(t.op().name == joints[std::size_t(tag.joint)].op.name);
    const bool across =
        (a.count(tag.joint) && b.count(tag.parent)) || (b.count(tag.joint) && a.count(tag.parent));
    CHECK(across);
  }
  std::set<int> all = a;
  all.insert(b.begin(), b.end());
  return all;
}

}  // namespace

TEST_CASE("builders tag each joint's nodes with its skeleton edge, the program keeps the tags",
          "[tree][builder]") {
  const SkeletonParts s = arm_skeleton();
  const auto grid = sampled_blend_grid();
  const NodeOperator contact =
      NodeOperator::grid_operator(grid, ops::Controller::preset("contact"), "contact");
  const NodeOperator bulge = NodeOperator::grid_operator(grid, ops::Controller::preset("bulge"), "bulge");
  std::vector<JointSetup> joints(5, JointSetup{contact, false, NodeRole::Contact});
  joints[2] = JointSetup{bulge, true, NodeRole::Bulge};  // elbow and wrist: a chain of bulge joints
  joints[3] = JointSetup{bulge, true, NodeRole::Bulge};
  for (const bool y2014 : {false, true}) {
    const CompositionTree t = y2014 ? build_tree_2014(s, joints) : build_tree_2013(s, joints);
    std::vector<NodeTag> tags;
    CHECK(check_tags(t, s, joints, tags).size() == 5);
    const Program program(t);
    REQUIRE(program.size() == tags.size());
    int bulges = 0;
    for (std::size_t i = 0; i < program.size(); ++i) {
      CHECK(program.tag(i).joint == tags[i].joint);
      CHECK(program.tag(i).parent == tags[i].parent);
      CHECK(program.tag(i).role == tags[i].role);
      bulges += program.tag(i).role == NodeRole::Bulge;
    }
    // 2013: one pair per bulge joint; 2014: the pair (upper arm, forearm) is at the bottom, the
    // wrist (hand under the paired forearm) joins it by its own bulge node.
    CHECK(bulges == 2);
  }
}

TEST_CASE("a leaf posed with a scale is its field stretched along its local axes, in every evaluator",
          "[tree][scale][unit]") {
  test::Rng rng(71);
  const auto sphere = std::make_shared<const SphereField>(Vec3f{0, 0, 0}, 1.0f);
  const auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.3f);
  const Rigid3f at_cap = random_rigid(rng, 0.5);
  const auto program = std::make_shared<const Program>(
      CompositionTree::node(NodeOperator::max(), CompositionTree::leaf(sphere, Rigid3f{}, 0),
                            CompositionTree::leaf(cap, at_cap, 1)));
  auto pose = std::make_shared<Pose>(*program);
  const Rigid3f T = random_rigid(rng, 1.0);
  const Vec3f S{1.5f, 0.6f, 0.9f};
  pose->set_transform_of(*program, 0, T, S);
  CHECK(pose->scales()[0] == S);
  const ProgramField field(program, pose);
  // Values: the sphere read at S⁻¹ Rᵀ (p − t), with the capsule by max.
  double worst_v = 0, worst_g = 0;
  int inside = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3f p = test::to_float(rng.vec(-2.5, 2.5));
    Vec3f local = T.apply_inverse(p);
    local = Vec3f{local.x / S.x, local.y / S.y, local.z / S.z};
    const float expect = std::max(sphere->eval(local).value, cap->eval(at_cap.apply_inverse(p)).value);
    const FieldSample s = field.eval(p);
    worst_v = std::max(worst_v, double(std::abs(s.value - expect)));
    // Gradients: central differences of the posed field (the chain rule through R S⁻¹).
    if (s.value > 0.05f && s.value < 0.95f) {
      ++inside;
      const float h = 1e-3f;
      Vec3f fd;
      for (int c = 0; c < 3; ++c) {
        Vec3f a = p, b = p;
        a[c] += h;
        b[c] -= h;
        fd[c] = (field.eval(a).value - field.eval(b).value) / (2 * h);
      }
      worst_g = std::max(worst_g, double(norm(fd - s.gradient)) / std::max(1.0, double(norm(fd))));
    }
    // The world box holds every point with a value.
    if (s.value > 0.f) {
      const Box3f b = pose->support();
      REQUIRE((p.x >= b.lo.x && p.y >= b.lo.y && p.z >= b.lo.z && p.x <= b.hi.x && p.y <= b.hi.y &&
               p.z <= b.hi.z));
    }
  }
  CHECK(inside > 100);
  CHECK(worst_v <= 1e-5);
  CHECK(worst_g <= 2e-2);
  // The batch (sparse) evaluator gives the scalar evaluator's results.
  std::vector<Vec3f> pts(2000);
  for (Vec3f& p : pts) p = test::to_float(rng.vec(-2.5, 2.5));
  std::vector<FieldSample> batch(pts.size());
  BatchEvaluator(*program, *pose).eval(pts.data(), pts.size(), batch.data());
  ScalarEvaluator scalar(*program, *pose);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const FieldSample a = scalar.eval(pts[i]);
    REQUIRE(std::abs(a.value - batch[i].value) <= 1e-6f);
    REQUIRE(norm(a.gradient - batch[i].gradient) <= 1e-5f * std::max(1.f, norm(a.gradient)));
  }
  // Scale 1 is the rigid pose bit for bit; bad scales are refused.
  Pose rigid(*program), unit(*program);
  rigid.set_transform_of(*program, 0, T);
  unit.set_transform_of(*program, 0, T, Vec3f{1, 1, 1});
  const Mat3f& ru = unit.leaves()[0].local_to_world.R;
  const Mat3f& rr = rigid.leaves()[0].local_to_world.R;
  CHECK(std::equal(ru.m, ru.m + 9, rr.m));
  CHECK_THROWS_WITH(unit.set_transform_of(*program, 0, T, Vec3f{1, 0, 1}),
                    Catch::Contains("pose leaf scale"));
  CHECK_THROWS_AS(unit.set_leaf_transform(*program, 0, T, Vec3f{1, -2, 1}), InputError);
  CHECK_THROWS_AS(unit.set_leaf_transform(*program, 0, T, Vec3f{std::nanf(""), 1, 1}), InputError);
}

TEST_CASE("scaled grid leaves: the host/device layout evaluator equals the sparse evaluator bit for bit",
          "[tree][scale][unit]") {
  test::Rng rng(19);
  for (int trial = 0; trial < 5; ++trial) {
    const Program program(random_tree(rng, rng.integer(2, 30), false, 1));
    REQUIRE(program.sparse());
    Pose pose(program);
    for (std::size_t k = 0; k < program.leaves().size(); ++k)
      pose.set_leaf_transform(
          program, k, random_rigid(rng, 1.0),
          Vec3f{float(rng.uniform(0.5, 2)), float(rng.uniform(0.5, 2)), float(rng.uniform(0.5, 2))});
    const TapeSparseLayout layout = sparse_layout(program, pose);
    const SparseEvaluator sparse(program, pose);
    int nonzero = 0;
    for (int k = 0; k < 3000; ++k) {
      const Vec3f p = test::to_float(rng.vec(-2.5, 2.5));
      const FieldSample a = sparse.eval(p), b = eval_sparse_layout(layout, p);
      REQUIRE(a.value == b.value);
      REQUIRE(a.gradient == b.gradient);
      nonzero += a.value != 0.f;
    }
    CHECK(nonzero > 100);
  }
}
