// SPDX-License-Identifier: MIT
// HRBF fitting: interpolation of the Hermite data, gradients against finite differences,
// conditioning and near-duplicate rules, bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "isokit/core/error.h"
#include "isokit/implicit/hrbf.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

/// `m` random points on an ellipsoid with semi-axes `ax` and their outward normals.
std::vector<HrbfSample> ellipsoid_samples(test::Rng& rng, int m, const Vec3d& ax, const Vec3d& centre) {
  std::vector<HrbfSample> s;
  for (int i = 0; i < m; ++i) {
    const Vec3d u = rng.unit();
    const Vec3d p{ax.x * u.x, ax.y * u.y, ax.z * u.z};
    Vec3d n{p.x / (ax.x * ax.x), p.y / (ax.y * ax.y), p.z / (ax.z * ax.z)};
    s.push_back({p + centre, n / norm(n)});
  }
  return s;
}

}  // namespace

TEST_CASE("HRBF interpolates its samples: d(v) = 0 and grad d(v) = n", "[hrbf]") {
  test::Rng rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    const Vec3d ax = rng.vec(0.2, 3.0);
    const Vec3d c = rng.vec(-5, 5);
    const int m = rng.integer(10, 60);
    const auto samples = ellipsoid_samples(rng, m, ax, c);
    const Hrbf h(samples);
    REQUIRE(h.samples().size() == samples.size());
    const double diag = 2 * norm(ax);
    for (const HrbfSample& s : samples) {
      const auto e = h.distance(s.position);
      CHECK(std::abs(e.value) <= 1e-6 * diag);
      CHECK(norm(e.gradient - s.normal) <= 1e-6);
    }
    CHECK(h.residual() <= 1e-6);
    CHECK(h.rcond() > 0);
    // Inside is negative (normals point outward), so the compact field is > 0.5 at the centre.
    CHECK(h.distance(c).value < 0);
  }
}

TEST_CASE("HRBF gradients agree with central differences", "[hrbf]") {
  test::Rng rng(12);
  const auto samples = ellipsoid_samples(rng, 40, {1.0, 0.6, 1.4}, {0.3, -0.2, 0.1});
  const auto hrbf = std::make_shared<const Hrbf>(samples);
  const double r = 1.4;
  const HrbfField field(hrbf, r, Box3f{{-4, -4, -4}, {4, 4, 4}});
  double worst_d = 0, worst_f = 0, worst_float = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p = rng.vec(-2.5, 2.5);
    const auto e = hrbf->distance(p);
    const Vec3d fd = test::central_gradient([&](const Vec3d& q) { return hrbf->distance(q).value; }, p, 1e-5);
    worst_d = std::max(worst_d, norm(e.gradient - fd) / std::max(1.0, norm(fd)));
    const auto f = field.eval_d(p);
    const Vec3d ffd = test::central_gradient([&](const Vec3d& q) { return field.eval_d(q).value; }, p, 1e-5);
    worst_f = std::max(worst_f, norm(f.gradient - ffd));
    const FieldSample ff = field.eval(test::to_float(p));
    worst_float = std::max(worst_float, std::abs(double(ff.value) - f.value));
  }
  CHECK(worst_d <= 1e-6);
  CHECK(worst_f <= 1e-6);
  CHECK(worst_float <= 1e-4);  // float evaluation of the same coefficients
}

TEST_CASE("HRBF near-duplicate samples are merged, cancelling ones are rejected", "[hrbf]") {
  test::Rng rng(13);
  auto samples = ellipsoid_samples(rng, 30, {1, 1, 1}, {0, 0, 0});
  auto dup = samples;
  for (int i = 0; i < 10; ++i) {
    HrbfSample s = samples[std::size_t(i)];
    s.position += Vec3d{1e-9, -1e-9, 0};
    dup.push_back(s);
  }
  const Hrbf merged(dup);
  CHECK(merged.samples().size() == samples.size());
  for (const HrbfSample& s : samples) CHECK(std::abs(merged.distance(s.position).value) <= 1e-6);

  // Without merging, the duplicated rows make the system singular: a clear error, never garbage.
  HrbfOptions no_merge;
  no_merge.merge_distance = 0;
  CHECK_THROWS_AS(Hrbf(dup, no_merge), InputError);

  auto opposite = samples;
  opposite.push_back({samples[0].position, -samples[0].normal});
  CHECK_THROWS_WITH(Hrbf(opposite, {}, "thumb"),
                    Catch::Contains("thumb") && Catch::Contains("opposite normals"));
}

TEST_CASE("HRBF rejects bad input by name", "[hrbf]") {
  test::Rng rng(14);
  auto s = ellipsoid_samples(rng, 10, {1, 1, 1}, {0, 0, 0});
  CHECK_THROWS_WITH(Hrbf({s[0], s[1], s[2]}, {}, "tip"),
                    Catch::Contains("tip") && Catch::Contains("at least 4"));
  auto nan = s;
  nan[3].position.y = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(Hrbf(nan, {}, "tip"), Catch::Contains("tip sample 3 position"));
  auto zero = s;
  zero[2].normal = {0, 0, 0};
  CHECK_THROWS_WITH(Hrbf(zero, {}, "tip"), Catch::Contains("tip sample 2 normal"));
  const auto hrbf = std::make_shared<const Hrbf>(s);
  CHECK_THROWS_AS(HrbfField(hrbf, -1.0, Box3f{{-3, -3, -3}, {3, 3, 3}}), InputError);
  // A box that cuts the field is refused.
  CHECK_THROWS_WITH(HrbfField(hrbf, 1.0, Box3f{{-1, -1, -1}, {1, 1, 1}}), Catch::Contains("cuts the field"));
}
