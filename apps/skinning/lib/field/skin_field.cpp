// SPDX-License-Identifier: MIT
#include "isokit/skinning/skin_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "isokit/core/error.h"
#include "isokit/implicit/evaluators.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/primitives.h"
#include "isokit/implicit/skeleton.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/grid_operators.h"
#include "isokit/skinning/rigid_pieces.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

namespace {

/// The node operator of `joint`, and its tag's role (2014: bulge joints form bulge pairs); a
/// grid operator's controller goes to `controller`. The 2013 blend is sampled into `blend_grid`
/// on first use when SkinSetup::blend_grid is set (one grid for every blend joint).
implicit::JointSetup joint_setup(const std::string& joint, JointOperator op, const SkinSetup& setup,
                                 TreeKind kind, const Progress& progress, operators::Controller& controller,
                                 std::shared_ptr<const operators::GridOperator>& blend_grid) {
  implicit::JointSetup js;
  switch (op) {
    case JointOperator::kUnion:
      js.op = implicit::NodeOperator::max();
      js.role = implicit::NodeRole::Union;
      break;
    case JointOperator::kBlend: {
      const operators::Controller blend = operators::Controller::preset("blend2013");
      if (setup.blend_grid && !blend_grid)
        blend_grid = std::make_shared<const operators::GridOperator>(
            operators::sampled_gradient_blend_2013(setup.operator_resolution, setup.operator_slices));
      js.op = setup.blend_grid ? implicit::NodeOperator::grid_operator(blend_grid, blend, "blend2013")
                               : implicit::NodeOperator::gradient_blend(blend);
      js.role = implicit::NodeRole::Blend;
      break;
    }
    case JointOperator::kBulge:
    case JointOperator::kContact:
    case JointOperator::kAuto: {
      const bool bulge = op == JointOperator::kBulge;
      const JointGridOperator g =
          joint_grid_operator(setup, joint, bulge ? op : JointOperator::kContact, progress);
      controller = g.controller;
      js.op = implicit::NodeOperator::grid_operator(g.grid, g.controller, bulge ? "bulge" : "contact");
      js.bulge_pair = bulge && kind == TreeKind::k2014;
      js.role = bulge ? implicit::NodeRole::Bulge : implicit::NodeRole::Contact;
      break;
    }
  }
  return js;
}

/// The bend of joint `child` from `parent`: the angle of the rotation between their skinning
/// matrices' rigid parts (0 at rest).
double bend_between(const Affine& parent, const Affine& child) {
  const Eigen::Matrix3d rel = rigid_part(parent).linear().transpose() * rigid_part(child).linear();
  return std::acos(std::clamp((rel.trace() - 1.0) / 2.0, -1.0, 1.0));
}

/// The scale of a part's leaf under skinning matrix `m` (a clip's scale keys): the stretch of
/// `m`, seen in the leaf's frame `leaf` (rigid), its diagonal (a shear is dropped); exactly 1 for
/// a rigid `m` (within kStretchTolerance).
Vec3f leaf_scale(const Affine& m, const Affine& leaf) {
  const Eigen::Matrix3d p = stretch_part(m);
  if ((p - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= kStretchTolerance)
    return Vec3f{1.f, 1.f, 1.f};
  const Eigen::Matrix3d local = leaf.linear().transpose() * p * leaf.linear();
  return Vec3f{float(local(0, 0)), float(local(1, 1)), float(local(2, 2))};
}

/// Several roots: the later ones hang under the first.
void hang_roots_under_first(std::vector<int>& parent) {
  int first_root = -1;
  for (std::size_t i = 0; i < parent.size(); ++i)
    if (parent[i] < 0) {
      if (first_root < 0)
        first_root = static_cast<int>(i);
      else
        parent[i] = first_root;
    }
}

}  // namespace

/// The skeleton of the fitted joints (compressed: joints without a primitive left out).
struct SkinField::Skeleton {
  implicit::SkeletonParts parts;
  std::vector<implicit::JointSetup> joints;
};

SkinField::SkinField(const FittedRig& fitted, const SkinSetup& setup, TreeKind tree, const Progress& progress)
    : fitted_(&fitted), kind_(tree == TreeKind::kAuto ? TreeKind::k2014 : tree) {
  Skeleton sk = compressed_skeleton(setup, progress);
  const implicit::CompositionTree t = kind_ == TreeKind::k2013
                                          ? implicit::build_tree_2013(sk.parts, sk.joints)
                                          : implicit::build_tree_2014(sk.parts, sk.joints);
  // operators.storage "auto": fixed16 for the 2013 tree, float32 for the 2014 tree (setup.h).
  const implicit::GridStorage storage = setup.operator_storage.value_or(
      kind_ == TreeKind::k2013 ? implicit::GridStorage::fixed16 : implicit::GridStorage::float32);
  program_ = std::make_shared<const implicit::Program>(t, implicit::ProgramOptions{storage});
  auto rest = std::make_shared<implicit::Pose>(*program_);
  pose_muscles(std::vector<Affine>(fitted.rig().joints.size(), Affine::Identity()), *rest);
  rest_ = rest;
  pose_ = rest_;
  if (setup.bulge_gate) find_bulge_gates();
}

SkinField::Skeleton SkinField::compressed_skeleton(const SkinSetup& setup, const Progress& progress) {
  const Rig& r = fitted_->rig();
  const int nj = static_cast<int>(r.joints.size());
  std::vector<int> index(static_cast<std::size_t>(nj), -1);
  Skeleton sk;
  std::shared_ptr<const operators::GridOperator> blend_grid;  // sampled on first use
  for (int j = 0; j < nj; ++j) {
    const BonePart& b = fitted_->bones()[j];
    if (!b.fitted) continue;
    const int p = fitted_->primitive_parent(j);
    index[j] = static_cast<int>(sk.parts.parent.size());
    sk.parts.parent.push_back(p >= 0 ? index[p] : -1);
    sk.parts.parts.push_back(b.fit.field());
    sk.parts.transforms.push_back(to_rigid3f(to_affine(b.fit.local_to_world)));
    joint_of_leaf_id_.push_back(j);
    const std::string& name = r.joints[j].name;
    const JointOperator op = setup.operator_for(name, kind_);
    joint_ops_.push_back(name + ": " + describe_joint_operator(setup, name, op));
    operators::Controller controller = operators::Controller::preset(setup.bulge_controller);
    sk.joints.push_back(joint_setup(name, op, setup, kind_, progress, controller, blend_grid));
    leaf_controllers_.push_back(controller);
  }
  hang_roots_under_first(sk.parts.parent);
  add_muscles(setup, index, progress, sk);
  if (setup.rigid_pieces && setup.piece_fields) add_pieces(setup, index, progress, sk);
  return sk;
}

/// Each muscle as one more part: a unit sphere leaf under its bone's part, joined by the muscle's
/// operator (a child part of the bone in either tree), posed as an ellipsoid (pose_muscles).
void SkinField::add_muscles(const SkinSetup& setup, const std::vector<int>& index, const Progress& progress,
                            Skeleton& sk) {
  const Rig& r = fitted_->rig();
  const std::vector<Eigen::Vector3d> joints_at = rest_joint_positions(r);
  std::shared_ptr<const operators::GridOperator> blend_grid;
  const auto sphere = std::make_shared<const implicit::SphereField>(Vec3f{0, 0, 0}, 1.0f);
  for (std::size_t k = 0; k < setup.muscles.size(); ++k) {
    const MuscleSetup& m = setup.muscles[k];
    const std::string w = setup.source + ".muscles[" + std::to_string(k) + "] ('" + m.name + "')";
    const int bone = r.joint_index(m.bone), driver = r.joint_index(m.driver);
    require(bone >= 0, w + ".bone", "names no joint ('" + m.bone + "')", "give a joint of the rig");
    require(index[std::size_t(bone)] >= 0, w + ".bone", "joint '" + m.bone + "' has no fitted part",
            "attach the muscle to a bone with skin");
    require(driver >= 0 && r.joints[std::size_t(driver)].parent >= 0, w + ".driver",
            "'" + m.driver + "' is not a joint with a parent", "give the joint whose bend drives the muscle");
    Eigen::Vector3d u = m.axis;
    if (u.squaredNorm() == 0) {
      for (std::size_t c = 0; c < r.joints.size() && u.squaredNorm() == 0; ++c)
        if (r.joints[c].parent == bone) u = joints_at[c] - joints_at[std::size_t(bone)];
      require(u.squaredNorm() > 0, w + ".axis", "is needed: the bone has no child joint to point along",
              "give the first semi-axis's direction");
    }
    u.normalize();
    const Eigen::Vector3d v = u.unitOrthogonal(), x = u.cross(v);
    MuscleLeaf leaf{static_cast<int>(sk.parts.parent.size()),
                    bone,
                    driver,
                    r.joints[std::size_t(driver)].parent,
                    Affine::Identity(),
                    m};
    leaf.rest.linear() << u, v, x;
    leaf.rest.translation() = m.center;
    sk.parts.parent.push_back(index[std::size_t(bone)]);
    sk.parts.parts.push_back(sphere);
    sk.parts.transforms.push_back(to_rigid3f(leaf.rest));
    operators::Controller unused = operators::Controller::preset(setup.bulge_controller);
    sk.joints.push_back(joint_setup(m.name, m.op, setup, kind_, progress, unused, blend_grid));
    joint_ops_.push_back("muscle " + m.name + " on " + m.bone + ": " +
                         (m.op == JointOperator::kUnion ? "union" : "blend") + ", driven by " + m.driver);
    muscles_.push_back(std::move(leaf));
  }
}

/// Each rigid piece as one more part: the distance field of its own mesh, under its bone's part
/// (the nearest fitted ancestor's), joined by union.
void SkinField::add_pieces(const SkinSetup& setup, const std::vector<int>& index, const Progress& progress,
                           Skeleton& sk) {
  const Rig& r = fitted_->rig();
  std::shared_ptr<const operators::GridOperator> blend_grid;
  std::vector<int> piece_of(static_cast<std::size_t>(r.rest.rows()), -1);
  const std::vector<RigidPiece> pieces = find_rigid_pieces(r);
  for (std::size_t k = 0; k < pieces.size(); ++k)
    for (int v : pieces[k].vertices) piece_of[std::size_t(v)] = int(k);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const RigidPiece& pc = pieces[k];
    const int bone =
        pc.joints[std::size_t(std::max_element(pc.weights.begin(), pc.weights.end()) - pc.weights.begin())];
    int owner = bone;
    while (owner >= 0 && index[std::size_t(owner)] < 0) owner = r.joints[std::size_t(owner)].parent;
    if (owner < 0) continue;  // no fitted part to hang it under
    implicit::MeshPart part;
    part.name = r.name + ": rigid piece " + std::to_string(k);
    std::vector<int> local(static_cast<std::size_t>(r.rest.rows()), -1);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (int v : pc.vertices) {
      local[std::size_t(v)] = int(part.vertices.size());
      const Eigen::Vector3d q = r.rest.row(v).cast<double>().transpose();
      part.vertices.push_back(Vec3d{q.x(), q.y(), q.z()});
      lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    }
    for (Eigen::Index t = 0; t < r.triangles.rows(); ++t)
      if (piece_of[std::size_t(r.triangles(t, 0))] == int(k))
        part.triangles.push_back({local[std::size_t(r.triangles(t, 0))],
                                  local[std::size_t(r.triangles(t, 1))],
                                  local[std::size_t(r.triangles(t, 2))]});
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    Eigen::Index longest = 0;
    (hi - lo).maxCoeff(&longest);
    axis[longest] = 0.5 * (hi - lo)[longest];
    const Eigen::Vector3d c = 0.5 * (lo + hi);
    part.bone_start = Vec3d{(c - axis).x(), (c - axis).y(), (c - axis).z()};
    part.bone_end = Vec3d{(c + axis).x(), (c + axis).y(), (c + axis).z()};
    implicit::PartFitOptions fo = setup.fit;
    fo.field = implicit::PartFitOptions::FieldKind::distance;
    implicit::FittedPart fit;
    try {
      fit = implicit::fit_part_distance(part, fo);
    } catch (const InputError&) {
      continue;  // a piece whose mesh gives no distance field keeps its bone's field only
    }
    const Affine rest = to_affine(fit.local_to_world);
    pieces_.push_back({static_cast<int>(sk.parts.parent.size()), bone, rest});
    sk.parts.parent.push_back(index[std::size_t(owner)]);
    sk.parts.parts.push_back(fit.field());
    sk.parts.transforms.push_back(to_rigid3f(rest));
    operators::Controller unused = operators::Controller::preset(setup.bulge_controller);
    sk.joints.push_back(
        joint_setup(part.name, JointOperator::kUnion, setup, kind_, progress, unused, blend_grid));
    joint_ops_.push_back("rigid piece " + std::to_string(k) + " on " + r.joints[std::size_t(bone)].name +
                         ": union");
  }
}

/// Each muscle moved rigidly with its bone and scaled by its driver's bend (MuscleSetup::curve).
void SkinField::pose_muscles(const std::vector<Affine>& skin, implicit::Pose& pose) const {
  for (const MuscleLeaf& m : muscles_) {
    const double f =
        m.setup.scale_at(bend_between(skin[std::size_t(m.driver_parent)], skin[std::size_t(m.driver)]));
    Vec3f s;
    for (int c = 0; c < 3; ++c)
      s[c] = static_cast<float>(m.setup.radii[c] * (m.setup.scaled[std::size_t(c)] ? f : 1.0));
    pose.set_transform_of(*program_, m.id, to_rigid3f(skin[std::size_t(m.bone)] * m.rest), s);
  }
}

void SkinField::find_bulge_gates() {
  // The bulge nodes, from the builders' tags: every node that composes a bulge joint, i.e. joins
  // a bone's side to its primitive parent's across that one skeleton edge — the bulge pairs at
  // the bottom of a 2014 tree and the pairs of a 2013 tree, and a bulge joint whose bones are
  // already paired (a chain of bulge joints: every other one). A root hung under the first root
  // has no primitive parent, and no gate.
  const implicit::Program& program = *program_;
  for (std::size_t i = 0; i < program.size(); ++i) {
    const implicit::NodeTag& tag = program.tag(i);
    if (program.instructions()[i].kind != implicit::OpKind::Grid || tag.role != implicit::NodeRole::Bulge ||
        tag.joint < 0)
      continue;
    const int child = joint_of_leaf_id_[std::size_t(tag.joint)];
    const int parent = fitted_->primitive_parent(child);
    if (parent < 0) continue;
    gates_.push_back({i, fitted_->bones()[std::size_t(parent)].joint,
                      fitted_->bones()[std::size_t(child)].joint, program.controller(i),
                      leaf_controllers_[std::size_t(tag.joint)]});
  }
}

std::shared_ptr<const implicit::Pose> SkinField::pose_of(const std::vector<Affine>& skin) const {
  const Rig& r = fitted_->rig();
  require(skin.size() == r.joints.size(), r.name + ": pose", "one skinning matrix per joint",
          "pass skinning_matrices()");
  auto pose = std::make_shared<implicit::Pose>(*rest_);
  for (std::size_t i = 0; i < joint_of_leaf_id_.size(); ++i) {
    const BonePart& b = fitted_->bones()[joint_of_leaf_id_[i]];
    const Affine leaf = to_affine(b.fit.local_to_world);
    pose->set_transform_of(*program_, static_cast<int>(i), to_rigid3f(skin[b.joint] * leaf),
                           leaf_scale(skin[b.joint], leaf));
  }
  pose_muscles(skin, *pose);
  for (const PieceLeaf& pc : pieces_)
    pose->set_transform_of(*program_, pc.id, to_rigid3f(skin[std::size_t(pc.bone)] * pc.rest));
  for (const BulgeGate& g : gates_) {
    // The bend: the rotation angle between the two joints' skinning rotations (0 at rest).
    const float cap = static_cast<float>(
        g.controller.eval(bend_between(skin[std::size_t(g.parent_joint)], skin[std::size_t(g.child_joint)])));
    operators::ControllerTable t = g.base;
    for (float& v : t.values) v = std::min(v, cap);
    pose->set_controller(*program_, g.instruction, t);
  }
  return pose;
}

void SkinField::set_pose(const std::vector<Affine>& skin) {
  pose_ = pose_of(skin);
}

track::FieldFunction SkinField::function(std::shared_ptr<const implicit::Pose> pose, bool contacts) const {
  require(pose != nullptr && pose->fits(*program_), fitted_->rig().name + ": field pose",
          "is not a pose of this field's program", "make it with SkinField::pose_of");
  std::shared_ptr<const implicit::Program> program = program_;
  if (!contacts) {
    // Fast path: the batched sparse evaluator (no per-node diagnostics).
    return [program, pose](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients, std::uint8_t*) {
      implicit::BatchEvaluator(*program, *pose).eval(p, n, values, gradients);
    };
  }
  return
      [program, pose](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients, std::uint8_t* contact) {
        implicit::ScalarEvaluator eval(*program, *pose);
        std::vector<implicit::NodeDiagnostics> diag(program->size());
        const auto& instr = program->instructions();
        for (std::size_t k = 0; k < n; ++k) {
          const implicit::FieldSample s = eval.eval(p[k], contact ? diag.data() : nullptr, true);
          values[k] = s.value;
          gradients[k] = s.gradient;
          if (contact) {
            std::uint8_t c = 0;
            for (std::size_t i = 0; i < instr.size(); ++i)
              if (instr[i].leaf < 0 && diag[i].evaluated && diag[i].on_contact) c = 1;
            contact[k] = c;
          }
        }
      };
}

}  // namespace isokit::skinning
