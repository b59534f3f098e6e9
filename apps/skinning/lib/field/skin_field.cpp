// SPDX-License-Identifier: MIT
#include "isokit/skinning/skin_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <numeric>

#include "isokit/core/error.h"
#include "isokit/implicit/skeleton.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/controller.h"
#include "isokit/skinning/deform.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

namespace {

std::shared_ptr<const operators::GridOperator> cached_operator(const std::string& preset, int res, int slices,
                                                               const Progress& progress) {
  static std::mutex m;
  static std::map<std::string, std::shared_ptr<const operators::GridOperator>> cache;
  const std::string key = preset + "/" + std::to_string(res) + "/" + std::to_string(slices);
  std::lock_guard<std::mutex> lock(m);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  operators::OperatorSpec spec = operators::preset_spec(preset, res);
  spec.slices = slices;
  operators::BiharmonicOptions bo;
  if (progress) bo.progress = [&](int done, int total) { progress("operator " + preset, done, total); };
  operators::BiharmonicOperatorGenerator gen(spec, bo);
  auto op = std::make_shared<const operators::GridOperator>(gen.generate());
  cache[key] = op;
  return op;
}

}  // namespace

SkinField::SkinField(const FittedRig& fitted, const SkinSetup& setup, TreeKind tree, const Progress& progress)
    : fitted_(&fitted),
      kind_(tree == TreeKind::kAuto ? TreeKind::k2014 : tree),
      bulge_controller_(operators::Controller::preset(setup.bulge_controller)) {
  const Rig& r = fitted.rig();
  const int nj = static_cast<int>(r.joints.size());
  // Compressed skeleton over fitted joints.
  std::vector<int> index(static_cast<std::size_t>(nj), -1);
  implicit::SkeletonParts sk;
  std::vector<implicit::JointSetup> joints;
  for (int j = 0; j < nj; ++j) {
    const BonePart& b = fitted.bones()[j];
    if (!b.fitted) continue;
    const int p = fitted.primitive_parent(j);
    index[j] = static_cast<int>(sk.parent.size());
    sk.parent.push_back(p >= 0 ? index[p] : -1);
    sk.parts.push_back(b.fit.field());
    sk.transforms.push_back(to_rigid3f(to_affine(b.fit.local_to_world)));
    joint_of_leaf_id_.push_back(j);
    const JointOperator op = setup.operator_for(r.joints[j].name, kind_);
    joint_ops_.push_back(r.joints[j].name + ": " + to_string(op));
    implicit::JointSetup js;
    switch (op) {
      case JointOperator::kUnion:
        js.op = implicit::NodeOperator::max();
        break;
      case JointOperator::kBlend:
        js.op = implicit::NodeOperator::gradient_blend(operators::Controller::preset("blend2013"));
        break;
      case JointOperator::kBulge:
        js.op = implicit::NodeOperator::grid_operator(
            cached_operator("bulge", setup.operator_resolution, setup.operator_slices, progress),
            operators::Controller::preset(setup.bulge_controller), "bulge");
        js.bulge_pair = kind_ == TreeKind::k2014;
        break;
      case JointOperator::kContact:
      case JointOperator::kAuto:
        js.op = implicit::NodeOperator::grid_operator(
            cached_operator("contact", setup.operator_resolution, setup.operator_slices, progress),
            operators::Controller::preset(setup.contact_controller), "contact");
        break;
    }
    joints.push_back(js);
  }
  // Several roots: hang the later ones under the first.
  int first_root = -1;
  for (std::size_t i = 0; i < sk.parent.size(); ++i)
    if (sk.parent[i] < 0) {
      if (first_root < 0)
        first_root = static_cast<int>(i);
      else
        sk.parent[i] = first_root;
    }
  const implicit::CompositionTree t = kind_ == TreeKind::k2013 ? implicit::build_tree_2013(sk, joints)
                                                               : implicit::build_tree_2014(sk, joints);
  tape_ = std::make_shared<implicit::Tape>(t);
  if (setup.bulge_gate) {
    // The bulge nodes: grid instructions that join a bone's subtree to its primitive parent's
    // (the one skeleton edge between the two operands' leaves), the child's joint using the bulge
    // operator: the bulge pairs at the bottom of a 2014 tree and the pairs of a 2013 tree, and a
    // bulge joint whose bones are already paired (a chain of bulge joints: every other one).
    // Post-order: a stack of the operands' leaf joints.
    const auto& instr = tape_->instructions();
    std::vector<std::vector<int>> operands;
    for (std::size_t i = 0; i < instr.size(); ++i) {
      if (instr[i].leaf >= 0) {
        operands.push_back({joint_of_leaf_id_[std::size_t(tape_->leaves()[std::size_t(instr[i].leaf)].id)]});
        continue;
      }
      std::vector<int> second = std::move(operands.back());
      operands.pop_back();
      std::vector<int>& first = operands.back();
      if (instr[i].kind == implicit::OpKind::Grid) {
        auto in = [](const std::vector<int>& set, int j) {
          return std::find(set.begin(), set.end(), j) != set.end();
        };
        bool found = false;
        for (const auto* sides : {&first, &second}) {
          const std::vector<int>& other = sides == &first ? second : first;
          for (int child : *sides) {
            const int parent = fitted.primitive_parent(child);
            if (parent < 0 || !in(other, parent)) continue;
            if (setup.operator_for(r.joints[std::size_t(child)].name, kind_) == JointOperator::kBulge)
              gates_.push_back({i, fitted.bones()[std::size_t(parent)].joint,
                                fitted.bones()[std::size_t(child)].joint, tape_->controller(i)});
            found = true;
            break;
          }
          if (found) break;
        }
      }
      first.insert(first.end(), second.begin(), second.end());
    }
  }
}

void SkinField::set_pose(const std::vector<Affine>& skin) {
  const Rig& r = fitted_->rig();
  require(skin.size() == r.joints.size(), r.name + ": pose", "one skinning matrix per joint",
          "pass skinning_matrices()");
  for (std::size_t i = 0; i < joint_of_leaf_id_.size(); ++i) {
    const BonePart& b = fitted_->bones()[joint_of_leaf_id_[i]];
    tape_->set_transform_of(static_cast<int>(i), to_rigid3f(skin[b.joint] * to_affine(b.fit.local_to_world)));
  }
  for (const BulgeGate& g : gates_) {
    // The bend: the rotation angle between the two joints' skinning rotations (0 at rest).
    const Eigen::Matrix3d rel = rigid_part(skin[std::size_t(g.parent_joint)]).linear().transpose() *
                                rigid_part(skin[std::size_t(g.child_joint)]).linear();
    const double c = std::clamp((rel.trace() - 1.0) / 2.0, -1.0, 1.0);
    const float cap = static_cast<float>(bulge_controller_.eval(std::acos(c)));
    operators::ControllerTable t = g.base;
    for (float& v : t.values) v = std::min(v, cap);
    tape_->set_controller(g.instruction, t);
  }
}

track::FieldFunction SkinField::function(bool contacts) const {
  std::shared_ptr<const implicit::Tape> tape = tape_;
  if (!contacts) {
    // Fast path: the tape's batched sparse evaluator (no per-node diagnostics).
    return [tape](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients, std::uint8_t*) {
      thread_local std::vector<implicit::FieldSample> out;
      out.resize(n);
      tape->eval_batch(p, n, out.data(), 0);
      for (std::size_t k = 0; k < n; ++k) {
        values[k] = out[k].value;
        gradients[k] = out[k].gradient;
      }
    };
  }
  return [tape](const Vec3f* p, std::size_t n, float* values, Vec3f* gradients, std::uint8_t* contact) {
    thread_local std::vector<implicit::NodeDiagnostics> diag;
    diag.resize(tape->size());
    const auto& instr = tape->instructions();
    for (std::size_t k = 0; k < n; ++k) {
      const implicit::FieldSample s = tape->eval(p[k], contact ? diag.data() : nullptr, true);
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
