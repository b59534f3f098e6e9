// Uses the installed headers and libraries; exits non-zero if a result is wrong.
#include <cmath>
#include <cstdio>
#include <memory>

#include <isokit/implicit/evaluators.h>
#include <isokit/implicit/grid_field.h>
#include <isokit/implicit/primitives.h>
#include <isokit/implicit/program_field.h>
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

  // A composition tree compiled once into a program, evaluated at two poses of it.
  const auto cap = std::make_shared<const implicit::CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.5f);
  const implicit::CompositionTree tree = implicit::CompositionTree::node(
      implicit::NodeOperator::max(), implicit::CompositionTree::leaf(cap, Rigid3f{}, 0),
      implicit::CompositionTree::leaf(cap, Rigid3f{}, 1));
  const auto program = std::make_shared<const implicit::Program>(tree);
  const auto rest = std::make_shared<const implicit::Pose>(*program);
  implicit::Pose moved(*program);
  Rigid3f shift;
  shift.t = Vec3f{2.f, 0.f, 0.f};
  moved.set_transform_of(*program, 1, shift);  // the second capsule, 2 units along x
  implicit::ScalarEvaluator at_rest(*program, *rest), at_moved(*program, moved);
  const float rest_value = at_rest.eval({2.5f, 0.f, 0.5f}).value;  // outside both capsules
  const float moved_value = at_moved.eval({2.5f, 0.f, 0.5f}).value;
  const implicit::ProgramField field(program, rest);
  const bool tree_ok = rest_value == 0.f && std::abs(moved_value - 0.5f) < 1e-6f &&
                       field.eval({0.5f, 0.f, 0.5f}).value == on_surface;

  const bool ok = std::abs(on_surface - 0.5f) < 1e-6f && std::abs(via_grid - 0.5f) < 2e-2f && u.g == 0.7f &&
                  adj.degree(0) == 2 && tree_ok;
  std::printf("consumer: surface %.6f grid %.6f union %.2f program %.6f / %.6f -> %s\n", on_surface, via_grid,
              u.g, rest_value, moved_value, ok ? "ok" : "WRONG");
  return ok ? 0 : 1;
}
