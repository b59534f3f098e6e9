// SPDX-License-Identifier: MIT
// CPU/CUDA agreement of the compiled program (issue 7, step 1): random trees of grid leaves (16³,
// random frames) composed by every operator kind, including sampled grid operators with the
// 2013 blend controller; then the same programs at a pose with every leaf moved
// (update_transforms).
// Without a CUDA device the program exits 77 (gpu_main.cpp; CTest: skipped, never passed).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "implicit/tree_fixtures.h"
#include "isokit/implicit/cuda/device_eval.h"
#include "isokit/implicit/cuda/device_tape.h"
#include "isokit/implicit/evaluators.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

// Tolerance: the kernel runs eval_sparse_layout (bit-identical to SparseEvaluator::eval on the
// host, tests/implicit) compiled with --fmad=false, so only device libm calls (tanf in the arc
// operators) may differ by an ulp; the bounds below leave room for that and nothing else.
// The largest differences are printed for docs/performance.md.
void compare(const Program& program, const Pose& pose, const std::vector<Vec3f>& pts,
             const std::vector<FieldSample>& gpu) {
  int nonzero = 0, identical = 0;
  float max_value = 0.f, max_gradient = 0.f;
  const SparseEvaluator cpu(program, pose);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const FieldSample c = cpu.eval(pts[i]);
    INFO("point " << i);
    REQUIRE(std::abs(c.value - gpu[i].value) <= 1e-6f);
    REQUIRE(norm(c.gradient - gpu[i].gradient) <= 1e-5f * (1.f + norm(c.gradient)));
    max_value = std::max(max_value, std::abs(c.value - gpu[i].value));
    max_gradient = std::max(max_gradient, norm(c.gradient - gpu[i].gradient));
    identical += c.value == gpu[i].value && c.gradient == gpu[i].gradient;
    nonzero += c.value != 0.f;
  }
  std::printf("program: %d of %zu points bit-identical, max |dvalue| %.3g, max |dgradient| %.3g\n", identical,
              pts.size(), double(max_value), double(max_gradient));
  CHECK(nonzero > int(pts.size()) / 10);  // the points do hit the primitives
}

}  // namespace

TEST_CASE("CUDA and CPU agree on compiled programs of grid leaves and operators", "[gpu]") {
  test::Rng rng(77);
  std::vector<Vec3f> pts(100000);
  for (auto& p : pts) p = test::to_float(rng.vec(-2.0, 2.0));
  std::vector<FieldSample> out(pts.size());
  for (int trial = 0; trial < 6; ++trial) {
    const Program program(test::random_tree(rng, rng.integer(2, 40), false, 1, 16));
    REQUIRE(program.sparse());
    Pose pose(program);
    cuda::DeviceTape device(program, pose);
    device.eval(pts.data(), pts.size(), out.data());
    compare(program, pose, pts, out);
    for (std::size_t k = 0; k < program.leaves().size(); ++k)
      pose.set_leaf_transform(program, k, test::random_rigid(rng, 1.0));
    device.update_transforms(program, pose);
    device.eval(pts.data(), pts.size(), out.data());
    compare(program, pose, pts, out);
  }
}

TEST_CASE("a device tape rejects leaves that are not grids", "[gpu]") {
  const auto cap = std::make_shared<const CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.3f);
  const Program program(CompositionTree::node(NodeOperator::max(), CompositionTree::leaf(cap, Rigid3f{}, 0),
                                              CompositionTree::leaf(cap, Rigid3f{}, 1)));
  const Pose pose(program);
  CHECK_THROWS_WITH(cuda::DeviceTape(program, pose),
                    Catch::Contains("program leaf 0") && Catch::Contains("grid"));
}
