// SPDX-License-Identifier: MIT
// Serial and parallel batch evaluation agree bit for bit, for every field kind and grain size.
#include <catch2/catch.hpp>

#include <cstring>
#include <memory>
#include <vector>

#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

TEST_CASE("batch evaluation: serial and parallel results are identical", "[implicit][batch]") {
  auto capsule = std::make_shared<CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 1, 0}, 0.3f);
  Rigid3f xf;
  xf.R = Mat3f{{0, -1, 0, 1, 0, 0, 0, 0, 1}};
  xf.t = {0.5f, 0.f, 0.2f};
  const TransformedField moved(capsule, xf);
  const GridField grid(*capsule);
  const SphereField sphere({0, 0, 0}, 0.8f);
  const std::vector<const Field*> fields{capsule.get(), &moved, &grid, &sphere};

  test::Rng rng(41);
  const std::size_t n = 100003;
  std::vector<Vec3f> points(n);
  for (auto& p : points) p = test::to_float(rng.vec(-1.5, 1.5));

  for (const Field* f : fields) {
    std::vector<FieldSample> serial(n), par(n);
    f->eval_batch(points.data(), n, serial.data(), 0);
    for (std::size_t grain : {1u, 97u, 1024u}) {
      f->eval_batch(points.data(), n, par.data(), grain);
      CHECK(std::memcmp(serial.data(), par.data(), n * sizeof(FieldSample)) == 0);
    }
    // The single-point path gives the same numbers as the batch path.
    for (std::size_t i = 0; i < n; i += 997) {
      const FieldSample s = f->eval(points[i]);
      CHECK(s.value == serial[i].value);
      CHECK(s.gradient == serial[i].gradient);
    }
    // Eigen convenience overload.
    Points P(static_cast<Eigen::Index>(n), 3);
    std::memcpy(P.data(), points.data(), n * sizeof(Vec3f));
    Eigen::VectorXf values;
    Points grads;
    f->eval_batch(P, values, grads);
    REQUIRE(values.size() == static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; i += 101) {
      const auto r = static_cast<Eigen::Index>(i);
      CHECK(values[r] == serial[i].value);
      CHECK(grads(r, 0) == serial[i].gradient.x);
      CHECK(grads(r, 2) == serial[i].gradient.z);
    }
  }
}
