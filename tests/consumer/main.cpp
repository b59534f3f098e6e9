// Uses the installed headers and libraries; exits non-zero if a result is wrong.
#include <cmath>
#include <cstdio>

#include <isokit/implicit/grid_field.h>
#include <isokit/implicit/primitives.h>
#include <isokit/operators/operator.h>
#include <isokit/track/mesh.h>

int main() {
  using namespace isokit;
  const implicit::CapsuleField capsule({0, 0, 0}, {0, 0, 1}, 0.5f);
  const implicit::GridField grid(capsule);
  const float on_surface = capsule.eval({0.5f, 0.f, 0.5f}).value;
  const float via_grid = grid.eval({0.5f, 0.f, 0.5f}).value;
  const auto u = operators::union_max(0.3f, 0.7f);
  track::Triangles tri(1, 3);
  tri << 0, 1, 2;
  const auto adj = track::vertex_adjacency(tri, 3);
  const bool ok = std::abs(on_surface - 0.5f) < 1e-6f && std::abs(via_grid - 0.5f) < 2e-2f && u.g == 0.7f &&
                  adj.degree(0) == 2;
  std::printf("consumer: surface %.6f grid %.6f union %.2f -> %s\n", on_surface, via_grid, u.g,
              ok ? "ok" : "WRONG");
  return ok ? 0 : 1;
}
