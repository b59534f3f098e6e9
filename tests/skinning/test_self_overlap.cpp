// SPDX-License-Identifier: MIT
// Property tests of the interpenetration volume (self_overlap.h): lens volumes of overlapping
// spheres, zero for touching and stacked bodies, independence from the mesh's orientation and from
// the parallel grain, open meshes closed at their borders, and the per-frame metric.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "isokit/core/error.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/self_overlap.h"
#include "mesh_fixture.h"

using namespace isokit;
using namespace isokit::skinning;
using testing::icosphere;
using testing::join;
using testing::kPi;
using testing::Mesh;

namespace {

/// The volume common to two balls of radius r whose centres are d apart (0 <= d <= 2r).
double lens_volume(double r, double d) {
  return kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12;
}

/// Volume of the polyhedron inscribed in the unit sphere (icosphere level `level`).
double polyhedron_volume(int level) {
  const Mesh s = icosphere(level);
  return enclosed_volume(s.v, s.f);
}

/// Axis-aligned box [lo, hi] as 12 outward triangles.
Mesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  std::vector<Eigen::Vector3d> v;
  for (int k = 0; k < 8; ++k)
    v.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  const std::vector<std::array<int, 3>> f = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                             {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                             {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return testing::from_lists(v, f);
}

Mesh rotated(const Mesh& m, const Eigen::Matrix3d& r) {
  Mesh out = m;
  for (Eigen::Index i = 0; i < m.v.rows(); ++i)
    out.v.row(i) = (r * m.v.row(i).cast<double>().transpose()).cast<float>().transpose();
  return out;
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

}  // namespace

TEST_CASE("two overlapping spheres enclose their lens twice", "[unit][metrics][overlap]") {
  const int level = 5;
  // The inscribed polyhedra are smaller than the balls: scale the lens by their volume ratio.
  const double shrink = polyhedron_volume(level) / (4.0 / 3.0 * kPi);
  for (const double d : {0.4, 0.8, 1.2, 1.6}) {
    CAPTURE(d);
    const Mesh m = join(icosphere(level), icosphere(level, 1, Eigen::Vector3d(d, 0.1 * d, -0.05 * d)));
    const SelfOverlap o = self_overlap(m.v, m.f);
    const double lens = lens_volume(1, d * std::sqrt(1 + 0.01 + 0.0025)) * shrink;
    CHECK(std::abs(o.overlap - lens) <= 0.02 * lens);
    const double ball = 4.0 / 3.0 * kPi * shrink;
    CHECK(std::abs(o.enclosed - (2 * ball - lens)) <= 0.01 * (2 * ball - lens));
    CHECK(o.open_columns == 0);
  }
}

TEST_CASE("touching and stacked bodies and a single body enclose nothing twice", "[unit][metrics][overlap]") {
  SECTION("one sphere") {
    const Mesh s = icosphere(3);
    const SelfOverlap o = self_overlap(s.v, s.f);
    CHECK(o.overlap == 0);
    CHECK(o.enclosed == Approx(enclosed_volume(s.v, s.f)).epsilon(0.02));
  }
  SECTION("spheres that touch at one point") {
    const Mesh m = join(icosphere(4), icosphere(4, 1, Eigen::Vector3d(2, 0, 0)));
    CHECK(self_overlap(m.v, m.f).overlap == 0);
  }
  SECTION("boxes pressed onto one face, side by side and stacked along the columns") {
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3d step = Eigen::Vector3d::Zero();
      step[axis] = 1;
      const Mesh m = join(box({0, 0, 0}, {1, 1, 1}), box(step, step + Eigen::Vector3d::Ones()));
      const SelfOverlap o = self_overlap(m.v, m.f);
      CHECK(o.overlap <= 1e-12);  // a zero-length segment between the faces at worst
      CHECK(o.enclosed == Approx(2).epsilon(0.02));
    }
  }
  SECTION("two boxes that pass into each other by a slab") {
    const Mesh m = join(box({0, 0, 0}, {1, 1, 1}), box({0, 0, 0.75}, {1, 1, 1.75}));
    CHECK(self_overlap(m.v, m.f).overlap == Approx(0.25).epsilon(0.02));
  }
}

TEST_CASE("the overlap does not depend on how the mesh is turned", "[unit][metrics][overlap]") {
  std::mt19937 rng(7);
  SECTION("a sphere and an ellipsoid through it: within 2 %") {
    Mesh ellipsoid = icosphere(4);
    for (Eigen::Index i = 0; i < ellipsoid.v.rows(); ++i)
      ellipsoid.v.row(i) = ellipsoid.v.row(i).cwiseProduct(Eigen::RowVector3f(1.5f, 0.5f, 0.4f)) +
                           Eigen::RowVector3f(1.2f, 0.1f, 0.f);
    const Mesh m = join(icosphere(4), ellipsoid);
    const double reference = self_overlap(m.v, m.f).overlap;
    REQUIRE(reference > 0.1);
    for (int k = 0; k < 8; ++k) {
      const Mesh r = rotated(m, random_rotation(rng));
      CHECK(self_overlap(r.v, r.f).overlap == Approx(reference).epsilon(0.02));
    }
  }
  SECTION("a sphere and a flat box through it: within a cell across the box") {
    // The box's 0.5-thick side aligned with the grid is the worst case of the column sampling:
    // one column more or less across it.
    const Mesh m = join(icosphere(4), box({0.3, -0.2, -0.3}, {2.5, 0.3, 0.2}));
    const SelfOverlap aligned = self_overlap(m.v, m.f);
    REQUIRE(aligned.overlap > 0);
    for (int k = 0; k < 8; ++k) {
      const Mesh r = rotated(m, random_rotation(rng));
      CHECK(self_overlap(r.v, r.f).overlap == Approx(aligned.overlap).epsilon(aligned.cell / 0.5));
    }
  }
}

TEST_CASE("the overlap is the same serially and in parallel, bit for bit", "[unit][metrics][overlap]") {
  const Mesh m = join(icosphere(4), icosphere(4, 0.8, Eigen::Vector3d(0.9, 0.2, 0.1)));
  SelfOverlapOptions serial, parallel;
  serial.grain = 0;
  parallel.grain = 64;
  serial.mark_triangles = parallel.mark_triangles = true;
  const SelfOverlap a = self_overlap(m.v, m.f, serial), b = self_overlap(m.v, m.f, parallel);
  CHECK(a.overlap == b.overlap);
  CHECK(a.enclosed == b.enclosed);
  CHECK(a.overlap_triangles == b.overlap_triangles);
  // The marked triangles are those of the two spheres inside each other: on both spheres.
  const int first = static_cast<int>(icosphere(4).f.rows());
  REQUIRE(!a.overlap_triangles.empty());
  CHECK(a.overlap_triangles.front() < first);
  CHECK(a.overlap_triangles.back() >= first);
}

TEST_CASE("an open mesh is measured closed at its borders", "[unit][metrics][overlap]") {
  const Mesh whole = join(icosphere(4), icosphere(4, 1, Eigen::Vector3d(1, 0, 0)));
  const double closed = self_overlap(whole.v, whole.f).overlap;
  // Cut a cap off the top of the first sphere, and flip the winding of the second sphere's far
  // cap (misoriented edges), both away from the lens: both are closed by cones, and a flipped
  // region enclosed once stays enclosed once (|w| = 1).
  Mesh open = whole;
  std::vector<Eigen::Index> keep;
  const Eigen::Index first = whole.f.rows() / 2;
  for (Eigen::Index f = 0; f < whole.f.rows(); ++f) {
    Eigen::Vector3f lo = whole.v.row(whole.f(f, 0)).transpose(), hi = lo;
    for (int c = 1; c < 3; ++c) {
      lo = lo.cwiseMin(whole.v.row(whole.f(f, c)).transpose());
      hi = hi.cwiseMax(whole.v.row(whole.f(f, c)).transpose());
    }
    if (f < first && lo.z() > 0.9f) continue;
    keep.push_back(f);
  }
  open.f.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    open.f.row(r) = whole.f.row(keep[k]);
    if (keep[k] >= first && open.v(open.f(r, 0), 0) > 1.8f) std::swap(open.f(r, 1), open.f(r, 2));
  }
  REQUIRE(open.f.rows() < whole.f.rows());
  const SelfOverlap o = self_overlap(open.v, open.f);
  CHECK(o.open_columns == 0);
  CHECK(o.overlap == Approx(closed).epsilon(0.02));
}

TEST_CASE("the frame metrics carry the new overlap as a share of the rest volume",
          "[unit][metrics][overlap]") {
  // Rest: two spheres apart; posed: the second moved into the first.
  const Mesh rest = join(icosphere(4), icosphere(4, 1, Eigen::Vector3d(2.5, 0, 0)));
  Mesh posed = rest;
  const Eigen::Index half = icosphere(4).v.rows();
  for (Eigen::Index i = half; i < posed.v.rows(); ++i) posed.v(i, 0) -= 1.5f;
  const FrameMetricsEvaluator evaluator(rest.v, rest.f);
  const FrameMetrics at_rest = evaluator.evaluate(rest.v, false);
  CHECK(at_rest.self_overlap == 0);
  CHECK(at_rest.self_overlap_new == 0);
  const FrameMetrics m = evaluator.evaluate(posed.v, false);
  const double shrink = polyhedron_volume(4) / (4.0 / 3.0 * kPi);
  CHECK(m.self_overlap == Approx(lens_volume(1, 1) * shrink).epsilon(0.02));
  CHECK(m.self_overlap_new == Approx(m.self_overlap / evaluator.rest_overlap().enclosed).epsilon(1e-12));
  CHECK(!new_overlap_triangles(rest.v, posed.v, rest.f).empty());
  CHECK(new_overlap_triangles(rest.v, rest.v, rest.f).empty());
  CHECK(std::isnan(evaluator.evaluate(posed.v, false, false).self_overlap));
}

TEST_CASE("bad input to the overlap is a one-line error", "[unit][metrics][overlap]") {
  Mesh m = icosphere(1);
  SelfOverlapOptions o;
  o.resolution = 0;
  CHECK_THROWS_WITH(self_overlap(m.v, m.f, o), Catch::Contains("resolution"));
  m.v(3, 1) = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(self_overlap(m.v, m.f), InputError);
  m.f(2, 0) = 10000;
  CHECK_THROWS_WITH(self_overlap(m.v, m.f), Catch::Contains("triangle 2"));
  const Mesh empty;
  CHECK(self_overlap(empty.v, empty.f).overlap == 0);
}

namespace {

/// The vertices of the meshes joined after the first `skin_vertices`: the rigid pieces.
std::vector<int> vertices_from(Eigen::Index skin_vertices, Eigen::Index all) {
  std::vector<int> v;
  for (Eigen::Index i = skin_vertices; i < all; ++i) v.push_back(static_cast<int>(i));
  return v;
}

/// `m` with the vertices [begin, end) moved by `d`.
track::Positions moved(const Mesh& m, Eigen::Index begin, Eigen::Index end, const Eigen::Vector3f& d) {
  track::Positions p = m.v;
  for (Eigen::Index i = begin; i < end; ++i) p.row(i) += d.transpose();
  return p;
}

}  // namespace

TEST_CASE("skin overlap: two rigid pieces passing into each other add nothing to the skin's",
          "[unit][metrics][overlap]") {
  // The skin: one ball. Two rigid pieces beside it (a sword and a hand guard), apart at rest.
  const Mesh skin = icosphere(4);
  const Mesh pieces =
      join(icosphere(3, 0.4, Eigen::Vector3d(3, 0, 0)), icosphere(3, 0.4, Eigen::Vector3d(4, 0, 0)));
  const Mesh m = join(skin, pieces);
  const Eigen::Index ns = skin.v.rows(), first_piece_end = ns + pieces.v.rows() / 2;
  SkinReference ref;
  ref.rigid_vertices = vertices_from(ns, m.v.rows());
  const FrameMetricsEvaluator eval(m.v, m.f, {}, ref);
  CHECK(eval.skin_triangles().rows() == skin.f.rows());
  // The first piece moves half into the second.
  const track::Positions posed = moved(m, ns, first_piece_end, {0.6f, 0, 0});
  const FrameMetrics f = eval.evaluate(posed, false);
  CHECK(f.self_overlap_new > 1e-3);
  CHECK(f.skin_overlap == 0);
  CHECK(f.skin_overlap_new == 0);
  CHECK(f.folded_new == -1);  // no weights: no folds
}

TEST_CASE("skin overlap: a skin passing into itself next to a rigid piece gives its own volume",
          "[unit][metrics][overlap]") {
  const int level = 4;
  // The skin: two balls 2.5 apart (an arm and a chest). A rigid piece, itself overlapping a
  // second one at rest already, sits beside them.
  const Mesh skin = join(icosphere(level), icosphere(level, 1, Eigen::Vector3d(2.5, 0, 0)));
  const Mesh pieces =
      join(icosphere(3, 0.4, Eigen::Vector3d(0, 3, 0)), icosphere(3, 0.4, Eigen::Vector3d(0.3, 3, 0)));
  const Mesh m = join(skin, pieces);
  const Eigen::Index ns = skin.v.rows(), half = skin.v.rows() / 2;
  SkinReference ref;
  ref.rigid_vertices = vertices_from(ns, m.v.rows());
  const FrameMetricsEvaluator eval(m.v, m.f, {}, ref);
  // The second ball moves 1.5 toward the first: their lens, 1.0 apart.
  const track::Positions posed = moved(m, half, ns, {-1.5f, 0, 0});
  const FrameMetrics f = eval.evaluate(posed, false);
  const track::Positions skin_alone = posed.topRows(ns);
  const SelfOverlap own = self_overlap(skin_alone, skin.f), own_rest = self_overlap(skin.v, skin.f);
  CHECK(f.skin_overlap == own.overlap);
  CHECK(f.skin_overlap_new == Approx((own.overlap - own_rest.overlap) / own_rest.enclosed));
  const double shrink = polyhedron_volume(level) / (4.0 / 3.0 * kPi);
  CHECK(std::abs(f.skin_overlap - lens_volume(1, 1.0) * shrink) <= 0.02 * lens_volume(1, 1.0));
  // The whole mesh counts the pieces' overlap too; its new share is the skin's over a larger body.
  CHECK(f.self_overlap > f.skin_overlap);
  CHECK(f.self_overlap_new > 0);
  // A rigid vertex index outside the mesh is a one-line error.
  ref.rigid_vertices = {static_cast<int>(m.v.rows())};
  CHECK_THROWS_AS(FrameMetricsEvaluator(m.v, m.f, {}, ref), InputError);
}
