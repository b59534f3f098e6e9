// SPDX-License-Identifier: MIT
// HRBF fitting and composition-tree throughput: fit time per bone (HRBF + 32^3 grid, and the
// HRBF alone), and program evaluation (value + gradient) of a 24-bone 2014 tree of grid primitives
// with grid contact operators, serial (one core) and parallel (TBB, all cores).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/program_field.h"
#include "isokit/implicit/skeleton.h"
#include "isokit/operators/grid_operator.h"

namespace {

using namespace isokit;
using namespace isokit::implicit;

/// A limb: tube of radius 0.12 along the bone (0,0,0)-(0,0,L), bulging slightly in the
/// middle, 24 rings x 24 segments (1104 triangles), open at both joints.
MeshPart limb(double L) {
  // Truncated values of π, kept: they are part of the benchmarked limb's shape, and isokit::kPi
  // would move its vertices (and the fitted field) in the last bits, so old and new builds would
  // no longer time the same input.
  constexpr double kBulgePi = 3.14159265, kRingPi = 3.14159265358979;
  MeshPart m;
  m.name = "limb";
  const int rings = 24, seg = 24;
  for (int r = 0; r < rings; ++r) {
    const double z = L * r / (rings - 1);
    const double rad = 0.12 * (1 + 0.2 * std::sin(kBulgePi * z / L));
    for (int s = 0; s < seg; ++s) {
      const double t = 2 * kRingPi * s / seg;
      m.vertices.push_back({rad * std::cos(t), rad * std::sin(t), z});
    }
  }
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < seg; ++s) {
      const int i0 = r * seg + s, i1 = r * seg + (s + 1) % seg;
      m.triangles.push_back({i0, i1, i1 + seg});
      m.triangles.push_back({i0, i1 + seg, i0 + seg});
    }
  m.bone_end = {0, 0, L};
  return m;
}

void BM_FitPart(benchmark::State& state) {
  const MeshPart part = limb(1.0);
  PartFitOptions o;
  o.sample_grid = state.range(0) != 0;
  for (auto _ : state) {
    FittedPart fp = fit_part(part, o);
    benchmark::DoNotOptimize(fp.local.get());
  }
  state.SetLabel(o.sample_grid ? "HRBF + 32^3 grid" : "HRBF only");
}
BENCHMARK(BM_FitPart)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

/// 24 bones: a spine of 4 and 5 chains of 4 bones; grid primitives from one fitted limb.
struct Rig {
  std::shared_ptr<ProgramField> field;
  std::vector<Vec3f> points;
};

const Rig& rig() {
  static const Rig r = [] {
    PartFitOptions o;
    const FittedPart fp = fit_part(limb(0.5), o);
    SkeletonParts s;
    std::vector<Vec3f> start, dir;
    auto add = [&](int parent, Vec3f a, Vec3f d) {
      s.parent.push_back(parent);
      s.parts.push_back(fp.grid);
      // bone frame: z along d
      const Rigid3d f = bone_frame({a.x, a.y, a.z}, {a.x + d.x, a.y + d.y, a.z + d.z});
      Rigid3f x;
      for (int i = 0; i < 9; ++i) x.R.m[i] = float(f.R.m[i]);
      x.t = a;
      s.transforms.push_back(x);
      return int(s.parent.size()) - 1;
    };
    int prev = add(-1, {0, 0, 0}, {0, 0, 0.5f});
    for (int i = 1; i < 4; ++i) prev = add(prev, {0, 0, 0.5f * i}, {0, 0, 0.5f});
    const int top = prev;
    for (int c = 0; c < 5; ++c) {
      const float ang = 2 * kPiF * float(c) / 5;
      const Vec3f d{0.5f * std::cos(ang) * 0.8f, 0.5f * std::sin(ang) * 0.8f, 0.3f};
      Vec3f a{0, 0, 2.0f};
      int p = top;
      for (int k = 0; k < 4; ++k) {
        p = add(p, a, d);
        a = a + d;
      }
    }
    // A 128^2 x 16 grid operator sampled from the 2013 blend (the tree's cost does not depend
    // on the values, only on the grid sizes).
    const NodeOperator contact = NodeOperator::grid_operator(
        std::make_shared<const operators::GridOperator>(operators::sampled_gradient_blend_2013(128, 16)),
        operators::Controller::preset("contact"), "contact");
    std::vector<JointSetup> joints(s.parent.size(), JointSetup{contact, false});
    Rig out;
    out.field = std::make_shared<ProgramField>(build_tree_2014(s, joints));
    // Points near the skin: random points within 0.2 of a random bone.
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1), t(0, 1);
    std::uniform_int_distribution<std::size_t> bone(0, s.parent.size() - 1);
    out.points.resize(1 << 16);
    for (auto& p : out.points) {
      const Rigid3f& x = s.transforms[bone(rng)];
      p = x.apply({0.2f * u(rng), 0.2f * u(rng), 0.5f * t(rng)});
    }
    return out;
  }();
  return r;
}

void BM_TreeEval(benchmark::State& state) {
  const Rig& r = rig();
  std::vector<FieldSample> out(r.points.size());
  const std::size_t grain = std::size_t(state.range(0));
  for (auto _ : state) {
    r.field->eval_batch(r.points.data(), r.points.size(), out.data(), grain);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(r.points.size()));
  state.SetLabel(std::to_string(r.field->program().leaves().size()) + " leaves, " +
                 std::to_string(r.field->program().size()) + " instructions, grain " + std::to_string(grain));
}
BENCHMARK(BM_TreeEval)->Arg(0)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
