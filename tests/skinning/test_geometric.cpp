// SPDX-License-Identifier: MIT
// The geometric methods beside DQS: Direct Delta Mush (ddm.h) and optimized centers of rotation
// (cor.h). Properties on procedural rigs: identity at rest, rigid motion, reduction to LBS, the
// twisted cylinder, Ω against a dense reference, and the setup keys' errors.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/cor.h"
#include "isokit/skinning/ddm.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/setup.h"
#include "mesh_fixture.h"

using namespace isokit;
using namespace isokit::skinning;

namespace {

const Rig& cylinder() {
  static const Rig rig = [] {
    CylinderOptions o;
    o.vertices = 1500;
    return make_cylinder(o);
  }();
  return rig;
}

const Rig& finger() {
  static const Rig rig = [] {
    FingerOptions o;
    o.vertices = 1500;
    return make_finger(o);
  }();
  return rig;
}

/// The geometric methods under test, each as a deformation of one rig.
struct Geometric {
  std::string name;
  std::function<void(const std::vector<Affine>&, track::Positions&, std::size_t)> deform;
};

std::vector<Geometric> methods_of(const Rig& rig) {
  const int nj = static_cast<int>(rig.joints.size());
  DdmOptions v1;
  v1.variant = DdmVariant::kV1;
  DdmOptions alpha;
  alpha.alpha = 0.3;
  auto d0 = std::make_shared<DirectDeltaMush>(rig.rest, rig.triangles, rig.weights, nj);
  auto d1 = std::make_shared<DirectDeltaMush>(rig.rest, rig.triangles, rig.weights, nj, v1);
  auto da = std::make_shared<DirectDeltaMush>(rig.rest, rig.triangles, rig.weights, nj, alpha);
  auto c = std::make_shared<CorSkinning>(rig.rest, rig.triangles, rig.weights);
  return {{"ddm v0", [d0](auto& s, auto& o, std::size_t g) { d0->deform(s, o, g); }},
          {"ddm v1", [d1](auto& s, auto& o, std::size_t g) { d1->deform(s, o, g); }},
          {"ddm alpha 0.3", [da](auto& s, auto& o, std::size_t g) { da->deform(s, o, g); }},
          {"cor", [c](auto& s, auto& o, std::size_t g) { c->deform(s, o, g); }}};
}

Pose peak(const Rig& rig, const std::string& bend) {
  return bend_animation(rig, {parse_bend(bend, rig)}, 3)[1];
}

/// Area of the polygon of `ring` vertices projected on the plane ⟂ `axis` through their mean
/// (sorted by angle about the mean).
double section_area(const track::Positions& p, const std::vector<int>& ring, const Eigen::Vector3d& axis) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int v : ring) mean += p.row(v).cast<double>().transpose();
  mean /= double(ring.size());
  const Eigen::Vector3d a = axis.unitOrthogonal(), b = axis.cross(a);
  std::vector<std::pair<double, Eigen::Vector2d>> pts;
  for (int v : ring) {
    const Eigen::Vector3d d = p.row(v).cast<double>().transpose() - mean;
    const Eigen::Vector2d q(d.dot(a), d.dot(b));
    pts.emplace_back(std::atan2(q.y(), q.x()), q);
  }
  std::sort(pts.begin(), pts.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  double area = 0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const Eigen::Vector2d& u = pts[k].second;
    const Eigen::Vector2d& w = pts[(k + 1) % pts.size()].second;
    area += 0.5 * (u.x() * w.y() - u.y() * w.x());
  }
  return std::abs(area);
}

}  // namespace

TEST_CASE("geometric methods: identity at the rest pose", "[skinning][geometric][unit]") {
  for (const Rig* rig : {&cylinder(), &finger()}) {
    const std::vector<Affine> skin = skinning_matrices(*rig, rest_pose(*rig));
    for (const Geometric& m : methods_of(*rig)) {
      INFO(rig->name << " " << m.name);
      track::Positions out;
      m.deform(skin, out, 1024);
      CHECK(max_displacement(out, rig->rest) <= 1e-6 * bbox_diagonal(rig->rest));
    }
  }
}

TEST_CASE("geometric methods: a rigid motion of the whole skeleton moves the mesh rigidly",
          "[skinning][geometric][unit]") {
  const Rig& rig = finger();
  // A bent pose, then the same rigid motion applied to every skinning matrix.
  const std::vector<Affine> bent = skinning_matrices(rig, peak(rig, "Finger2:x:90"));
  Affine motion = Affine::Identity();
  motion.linear() = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, -0.5).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(3.0, -1.0, 0.5);
  std::vector<Affine> moved = bent;
  for (Affine& a : moved) a = motion * a;
  for (const Geometric& m : methods_of(rig)) {
    INFO(m.name);
    track::Positions a, b;
    m.deform(bent, a, 1024);
    m.deform(moved, b, 1024);
    track::Positions expected(a.rows(), 3);
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      expected.row(i) = (motion * a.row(i).cast<double>().transpose()).cast<float>().transpose();
    CHECK(max_displacement(b, expected) <= 1e-6 * bbox_diagonal(rig.rest));
    // and the identity skeleton moved rigidly moves the rest mesh rigidly
    std::vector<Affine> rigid(rig.joints.size(), motion);
    m.deform(rigid, b, 1024);
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      expected.row(i) = (motion * rig.rest.row(i).cast<double>().transpose()).cast<float>().transpose();
    CHECK(max_displacement(b, expected) <= 1e-6 * bbox_diagonal(rig.rest));
  }
}

TEST_CASE("geometric methods: serial and parallel runs agree bit for bit", "[skinning][geometric][unit]") {
  const Rig& rig = cylinder();
  const std::vector<Affine> skin = skinning_matrices(rig, peak(rig, "Bone1:x:120"));
  for (const Geometric& m : methods_of(rig)) {
    INFO(m.name);
    track::Positions serial, parallel;
    m.deform(skin, serial, 0);
    m.deform(skin, parallel, 64);
    CHECK(serial == parallel);
  }
}

TEST_CASE("ddm: one bone per vertex and no smoothing is LBS", "[skinning][geometric][unit]") {
  Rig rig = finger();
  // Each vertex's largest weight alone.
  SkinWeights one;
  one.offsets.push_back(0);
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
    int best = rig.weights.offsets[v];
    for (int k = rig.weights.offsets[v]; k < rig.weights.offsets[v + 1]; ++k)
      if (rig.weights.weights[k] > rig.weights.weights[best]) best = k;
    one.joints.push_back(rig.weights.joints[best]);
    one.weights.push_back(1.0f);
    one.offsets.push_back(static_cast<int>(one.joints.size()));
  }
  DdmOptions o;
  o.smoothing_steps = 0;
  const std::vector<Affine> skin = skinning_matrices(rig, peak(rig, "Finger1:x:120"));
  for (const SkinWeights* w : {&one, &rig.weights}) {  // with no smoothing, any weights give LBS
    const DirectDeltaMush ddm(rig.rest, rig.triangles, *w, static_cast<int>(rig.joints.size()), o);
    track::Positions a, b;
    ddm.deform(skin, a);
    linear_blend(*w, skin, rig.rest, b);
    CHECK(max_displacement(a, b) <= 1e-6 * bbox_diagonal(rig.rest));
  }
}

TEST_CASE("cor: a twisted cylinder keeps its cross-section, where LBS collapses",
          "[skinning][geometric][unit]") {
  const Rig& rig = cylinder();
  const std::vector<Affine> skin = skinning_matrices(rig, peak(rig, "Bone1:y:150"));
  // The ring of vertices at the joint (y = 1, the 50/50 blend), away from the caps.
  std::vector<int> ring;
  double best = 1e9;
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v)
    best = std::min(best, std::abs(double(rig.rest(v, 1)) - 1.0));
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v)
    if (std::abs(double(rig.rest(v, 1)) - 1.0) <= best + 1e-6) ring.push_back(static_cast<int>(v));
  REQUIRE(ring.size() >= 12);
  const Eigen::Vector3d axis(0, 1, 0);
  const double rest_area = section_area(rig.rest, ring, axis);
  const CorSkinning cor(rig.rest, rig.triangles, rig.weights);
  track::Positions c, l;
  cor.deform(skin, c);
  linear_blend(rig.weights, skin, rig.rest, l);
  CHECK(std::abs(section_area(c, ring, axis) / rest_area - 1.0) <= 0.02);
  CHECK(section_area(l, ring, axis) / rest_area < 0.5);
  // the centers of the ring lie near the bone axis
  for (int v : ring)
    if (cor.has_center(v)) CHECK(Eigen::Vector2d(cor.center(v).x(), cor.center(v).z()).norm() < 0.05);
}

TEST_CASE("ddm: the precomputed Ω match a dense reference solve", "[skinning][geometric][unit]") {
  const testing::Mesh m = testing::icosphere(2);
  const Eigen::Index n = m.v.rows();
  // Three bones by height, smooth weights summing to one.
  SkinWeights w;
  w.offsets.push_back(0);
  Eigen::MatrixXd wd = Eigen::MatrixXd::Zero(n, 3);
  for (Eigen::Index v = 0; v < n; ++v) {
    const double y = m.v(v, 1);
    Eigen::Vector3d raw(std::exp(-4 * (y + 1) * (y + 1)), std::exp(-4 * y * y),
                        std::exp(-4 * (y - 1) * (y - 1)));
    raw /= raw.sum();
    for (int j = 0; j < 3; ++j) {
      w.joints.push_back(j);
      w.weights.push_back(static_cast<float>(raw[j]));
      wd(v, j) = double(w.weights.back());
    }
    w.offsets.push_back(static_cast<int>(w.joints.size()));
  }
  const double lambda = GENERATE(0.5, 3.0);
  const double alpha = GENERATE(0.0, 0.25);
  DdmOptions o;
  o.lambda = lambda;
  o.alpha = alpha;
  o.smoothing_steps = 2;
  o.prune = 0;
  const DirectDeltaMush ddm(m.v, m.f, w, 3, o);
  // Dense: B = ((I + λL)⁻¹)^p with L = I − D⁻¹A.
  Eigen::MatrixXd adj = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index t = 0; t < m.f.rows(); ++t)
    for (int c = 0; c < 3; ++c) adj(m.f(t, c), m.f(t, (c + 1) % 3)) = adj(m.f(t, (c + 1) % 3), m.f(t, c)) = 1;
  const Eigen::VectorXd deg = adj.rowwise().sum();
  const Eigen::MatrixXd lap = Eigen::MatrixXd::Identity(n, n) - deg.cwiseInverse().asDiagonal() * adj;
  const Eigen::MatrixXd step = (Eigen::MatrixXd::Identity(n, n) + lambda * lap).inverse();
  const Eigen::MatrixXd b = (1 - alpha) * step * step + alpha * Eigen::MatrixXd::Identity(n, n);
  double worst = 0, scale = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) {
      Eigen::Matrix4d ref = Eigen::Matrix4d::Zero();
      for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Vector4d p(m.v(k, 0), m.v(k, 1), m.v(k, 2), 1.0);
        ref += b(i, k) * wd(k, j) * p * p.transpose();
      }
      worst = std::max(worst, (ddm.omega(static_cast<int>(i), j) - ref).cwiseAbs().maxCoeff());
      scale = std::max(scale, ref.cwiseAbs().maxCoeff());
    }
  INFO("lambda " << lambda << " alpha " << alpha);
  CHECK(worst <= 1e-10 * scale);
  CHECK(ddm.stored_pairs() == static_cast<std::size_t>(n) * 3);
}

TEST_CASE("ddm: pruning keeps the storage sparse", "[skinning][geometric][unit]") {
  const Rig& rig = finger();
  const DirectDeltaMush ddm(rig.rest, rig.triangles, rig.weights, static_cast<int>(rig.joints.size()));
  CHECK(ddm.stored_pairs() < static_cast<std::size_t>(rig.rest.rows()) * rig.joints.size());
  CHECK(ddm.precompute_seconds() > 0);
}

TEST_CASE("geometric methods: bad parameters are one-line errors naming the key",
          "[skinning][geometric][unit]") {
  const auto [text, key] = GENERATE(table<std::string, std::string>({
      {R"({"ddm": {"lambda": -1}})", "s.json.ddm.lambda"},
      {R"({"ddm": {"smoothing_steps": 1000}})", "s.json.ddm.smoothing_steps"},
      {R"({"ddm": {"alpha": 2}})", "s.json.ddm.alpha"},
      {R"({"ddm": {"kappa": -0.5}})", "s.json.ddm.kappa"},
      {R"({"ddm": {"prune": 0.9}})", "s.json.ddm.prune"},
      {R"({"ddm": {"variant": "v7"}})", "s.json.ddm.variant"},
      {R"({"ddm": {"steps": 3}})", "steps"},
      {R"({"cor": {"sigma": 0}})", "s.json.cor.sigma"},
      {R"({"cor": {"fallback": "none"}})", "s.json.cor.fallback"},
      {R"({"projector": {"initial": "lbs"}})", "s.json.projector.initial"},
      {R"({"tracker": {"anchor": "rigid"}})", "s.json.tracker.anchor"},
  }));
  INFO(text);
  try {
    (void)setup_from_json(text, "s.json");
    FAIL("no error");
  } catch (const InputError& e) {
    const std::string msg = e.what();
    INFO(msg);
    CHECK(msg.find(key) != std::string::npos);
    CHECK(msg.find('\n') == std::string::npos);
  }
  const SkinSetup ok = setup_from_json(
      R"({"ddm": {"smoothing_steps": 2, "lambda": 1.5, "variant": "v1"}, "cor": {"sigma": 0.2, "fallback": "dqs"},
          "projector": {"initial": "ddm"}, "tracker": {"anchor": "cor"}})",
      "s.json");
  CHECK(ok.ddm.smoothing_steps == 2);
  CHECK(ok.ddm.variant == DdmVariant::kV1);
  CHECK(ok.cor.fallback == CorFallback::kDqs);
  CHECK(ok.projector_initial == InitialSkinning::kDdm);
  CHECK(ok.tracker_anchor == InitialSkinning::kCor);
}

TEST_CASE("pipeline: ddm and cor are methods, and implicit2013 starts from them",
          "[skinning][geometric][unit]") {
  CHECK(method_from_string("ddm") == Method::kDdm);
  CHECK(method_from_string("cor") == Method::kCor);
  const Rig& rig = cylinder();
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:90", rig)}, 5);
  BakeOptions quick;
  quick.self_intersections = false;
  for (const char* initial : {"ddm", "cor"}) {
    Skinner sk(rig,
               setup_from_json(std::string(R"({"projector": {"initial": ")") + initial + "\"}}", "s.json"));
    for (Method m : {Method::kDdm, Method::kCor, Method::kImplicit2013}) {
      INFO(initial << " " << to_string(m));
      const BakeResult r = sk.bake(m, poses, quick);
      CHECK(r.rest_recovery <= (m == Method::kImplicit2013 ? 1e-3 : 1e-6));
      CHECK(max_displacement(r.frames[2], rig.rest) > 0.05);
      CHECK(r.setup_seconds > 0);
    }
  }
}

TEST_CASE("pipeline: tracking2014 pins masked vertices at their ddm / cor position with tracker.anchor",
          "[skinning][geometric][unit]") {
  // Vertices painted 0 are pinned at their anchor: the partition joint's rigid transform by
  // default, the geometric method's position with tracker.anchor (bit for bit: it is the anchor).
  Rig rig = cylinder();
  rig.relax_mask.assign(std::size_t(rig.rest.rows()), 1.0f);
  std::vector<int> painted;
  for (Eigen::Index v = 0; v < rig.rest.rows(); v += 7) {
    rig.relax_mask[std::size_t(v)] = 0.0f;
    painted.push_back(int(v));
  }
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:90", rig)}, 5);
  BakeOptions quick;
  quick.self_intersections = false;
  double moved = 0;
  for (const char* anchor : {"ddm", "cor"}) {
    INFO(anchor);
    const Method geometric = method_from_string(anchor);
    Skinner sk(rig, setup_from_json(std::string(R"({"tracker": {"anchor": ")") + anchor + "\"}}", "s.json"));
    const BakeResult tracked = sk.bake(Method::kTracking2014, poses, quick);
    const BakeResult reference = sk.bake(geometric, poses, quick);
    for (std::size_t f = 0; f < poses.size(); ++f)
      for (int v : painted) CHECK(tracked.frames[f].row(v) == reference.frames[f].row(v));
    Skinner plain(rig);
    const BakeResult rigid = plain.bake(Method::kTracking2014, poses, quick);
    for (int v : painted)
      moved = std::max(moved, double((rigid.frames[2].row(v) - tracked.frames[2].row(v)).norm()));
  }
  CHECK(moved > 1e-3);  // the default anchors (rigid) are elsewhere
}
