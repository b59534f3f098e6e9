// SPDX-License-Identifier: MIT
#include "isokit/skinning/animation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/deform.h"

namespace isokit::skinning {

namespace {

int parse_axis(const std::string& a, const std::string& where) {
  if (a == "x" || a == "X") return 0;
  if (a == "y" || a == "Y") return 1;
  if (a == "z" || a == "Z") return 2;
  throw InputError(where + ": unknown axis '" + a + "'; use x, y or z");
}

std::string joint_list(const Rig& rig) {
  std::string s;
  for (std::size_t j = 0; j < rig.joints.size() && j < 60; ++j) s += (j ? ", " : "") + rig.joints[j].name;
  if (rig.joints.size() > 60) s += ", ...";
  return s;
}

int find_joint(const Rig& rig, const std::string& name, const std::string& where) {
  int j = rig.joint_index(name);
  if (j < 0 && !name.empty() &&
      std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    j = std::stoi(name);
    require(j < static_cast<int>(rig.joints.size()), where, "joint index " + name + " out of range",
            "use 0.." + std::to_string(rig.joints.size() - 1));
  }
  require(j >= 0, where, "unknown joint '" + name + "'", "joints of " + rig.name + ": " + joint_list(rig));
  return j;
}

Eigen::Matrix3d axis_rotation(int axis, double degrees) {
  return Eigen::AngleAxisd(degrees * kPi / 180.0, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

}  // namespace

BendSpec parse_bend(const std::string& text, const Rig& rig) {
  const std::string where = "--bend " + text;
  const auto c2 = text.rfind(':');
  require(c2 != std::string::npos && c2 > 0, where, "expected JOINT:AXIS:DEGREES",
          "e.g. --bend LeftForeArm:z:150");
  const auto c1 = text.rfind(':', c2 - 1);
  require(c1 != std::string::npos, where, "expected JOINT:AXIS:DEGREES", "e.g. --bend LeftForeArm:z:150");
  BendSpec b;
  b.joint = find_joint(rig, text.substr(0, c1), where);
  b.axis = parse_axis(text.substr(c1 + 1, c2 - c1 - 1), where);
  const std::string deg = text.substr(c2 + 1);
  char* end = nullptr;
  b.degrees = std::strtod(deg.c_str(), &end);
  require(!deg.empty() && end && *end == '\0' && std::isfinite(b.degrees) && std::abs(b.degrees) <= 360,
          where, "bad angle '" + deg + "'", "give degrees in [-360, 360]");
  return b;
}

std::vector<BendSpec> crouch_bends(const Rig& rig) {
  std::vector<std::string> specs = {
      "Spine:x:10",     "Spine1:x:10",     "Spine2:x:10",      "Neck:x:15",         "Head:x:10",
      "LeftArm:x:30",   "RightArm:x:30",   "LeftForeArm:x:90", "RightForeArm:x:90", "LeftHand:x:30",
      "RightHand:x:30", "LeftUpLeg:x:-45", "RightUpLeg:x:-30", "LeftLeg:x:90",      "RightLeg:x:60",
      "LeftFoot:x:20",  "RightFoot:x:20"};
  for (const char* side : {"Left", "Right"})
    for (const char* finger : {"Thumb", "Index", "Middle", "Pinky"})
      for (int k = 1; k <= 3; ++k)
        specs.push_back(std::string(side) + "Hand" + finger + std::to_string(k) + ":x:45");
  std::vector<BendSpec> out;
  for (const std::string& s : specs) {
    const std::string joint = s.substr(0, s.find(':'));
    for (const Joint& j : rig.joints)
      if (j.name == joint) out.push_back(parse_bend(s, rig));
  }
  return out;
}

std::vector<Pose> bend_animation(const Rig& rig, const std::vector<BendSpec>& bends, int frames) {
  require(frames >= 3, "--frames", "need at least 3 frames (got " + std::to_string(frames) + ")",
          "rest, peak and rest again");
  const Pose rest = rest_pose(rig);
  std::vector<Pose> out;
  const int peak = frames / 2;
  for (int f = 0; f < frames; ++f) {
    const double t = f <= peak ? double(f) / peak : double(frames - 1 - f) / double(frames - 1 - peak);
    Pose p = rest;
    for (const BendSpec& b : bends) {
      Affine rot = Affine::Identity();
      rot.linear() = axis_rotation(b.axis, b.degrees * t);
      p[b.joint] = p[b.joint] * rot;
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<Pose> clip_animation(const Rig& rig, const std::string& name) {
  std::string names;
  for (const Clip& c : rig.clips) {
    if (c.name == name) {
      require(c.frame_count() > 0, rig.name + ": clip '" + name + "'", "has no frames",
              "choose another clip");
      return clip_frames(c);
    }
    names += (names.empty() ? "" : ", ") + c.name;
  }
  throw InputError(rig.name + ": no clip named '" + name + "'; clips: " + (names.empty() ? "(none)" : names));
}

Pose interpolate(const Pose& a, const Pose& b, double t) {
  Pose out(a.size());
  for (std::size_t j = 0; j < a.size(); ++j) {
    const Affine ra = rigid_part(a[j]), rb = rigid_part(b[j]);
    // Scale/shear part S with A = R S (kept linear).
    const Eigen::Matrix3d sa = ra.linear().transpose() * a[j].linear();
    const Eigen::Matrix3d sb = rb.linear().transpose() * b[j].linear();
    const Eigen::Quaterniond qa(Eigen::Matrix3d(ra.linear())), qb(Eigen::Matrix3d(rb.linear()));
    out[j] = Affine::Identity();
    out[j].linear() = qa.slerp(t, qb).toRotationMatrix() * ((1 - t) * sa + t * sb);
    out[j].translation() = (1 - t) * a[j].translation() + t * b[j].translation();
  }
  return out;
}

double max_rotation_between(const Pose& a, const Pose& b) {
  double m = 0;
  for (std::size_t j = 0; j < a.size() && j < b.size(); ++j) {
    Affine d = Affine::Identity();
    d.linear() = rigid_part(a[j]).linear().transpose() * rigid_part(b[j]).linear();
    m = std::max(m, rotation_angle(d));
  }
  return m;
}

int substeps(const Rig& rig, const Pose& a, const Pose& b, const SubstepOptions& o) {
  int n = 1;
  const Pose rest = rest_pose(rig);
  for (std::size_t j = 0; j < a.size(); ++j) {
    Affine d = Affine::Identity();
    d.linear() = rigid_part(a[j]).linear().transpose() * rigid_part(b[j]).linear();
    const double step = rotation_angle(d);
    if (step <= 0) continue;
    if (o.paper_rule || o.fold_rule) {
      // Bending angle: the joint's rotation away from rest, at either end of the step.
      Affine ea = Affine::Identity(), eb = Affine::Identity();
      ea.linear() = rigid_part(rest[j]).linear().transpose() * rigid_part(a[j]).linear();
      eb.linear() = rigid_part(rest[j]).linear().transpose() * rigid_part(b[j]).linear();
      const double bend = std::max(rotation_angle(ea), rotation_angle(eb));
      const double floor = 3.0 * o.min_step_rad;
      double limit = std::numeric_limits<double>::infinity();
      if (o.paper_rule) limit = std::max(bend, floor) / 3.0;
      if (o.fold_rule) limit = std::min(limit, std::max(kPi - bend, floor) / 3.0);
      n = std::max(n, static_cast<int>(std::ceil(step / limit - 1e-9)));
    }
    if (o.max_step_rad > 0) n = std::max(n, static_cast<int>(std::ceil(step / o.max_step_rad - 1e-9)));
  }
  return std::min(n, o.max_substeps);
}

std::vector<Pose> pose_script_from_json(const Rig& rig, const std::string& text, const std::string& source) {
  using nlohmann::json;
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw InputError(source + ": not valid JSON (" + e.what() + "); fix the file");
  }
  require(j.is_object() && j.contains("keys") && j["keys"].is_array() && !j["keys"].empty(), source,
          "needs a non-empty \"keys\" array",
          R"(e.g. {"keys": [{"frame": 0, "joints": {"LeftForeArm": [["z", 90]]}}]})");
  const Pose rest = rest_pose(rig);
  std::vector<std::pair<int, Pose>> keys;
  for (std::size_t k = 0; k < j["keys"].size(); ++k) {
    const json& key = j["keys"][k];
    const std::string where = source + ": keys[" + std::to_string(k) + "]";
    require(key.is_object() && key.contains("frame") && key["frame"].is_number_integer(), where,
            "needs an integer \"frame\"", "frames are 0, 1, 2, ... in increasing order");
    const auto frame64 = key["frame"].get<std::int64_t>();
    require(frame64 >= 0 && frame64 <= 100000 && (keys.empty() || frame64 > keys.back().first), where,
            "frames must increase from 0 and be at most 100000 (got " + std::to_string(frame64) + ")",
            "sort the keys by frame");
    const auto frame = static_cast<int>(frame64);
    // The script expands to (last frame + 1) poses: bounded as a clip's frames are (rig.h).
    const double samples = double(frame + 1) * double(std::max<std::size_t>(rig.joints.size(), 1));
    require(samples <= double(kMaxClipSamples), where,
            "frame " + std::to_string(frame) + " makes the script " + format_number(samples) +
                " joint transforms, more than the " + std::to_string(kMaxClipSamples) +
                " an animation may have",
            "use fewer frames");
    Pose p = rest;
    if (key.contains("joints")) {
      require(key["joints"].is_object(), where + ".joints", "must be an object",
              "joint name -> [[axis, degrees], ...]");
      for (auto it = key["joints"].begin(); it != key["joints"].end(); ++it) {
        const std::string w = where + ".joints." + it.key();
        const int jt = find_joint(rig, it.key(), w);
        require(it.value().is_array(), w, "must be a list of [axis, degrees]", R"(e.g. [["z", 90]])");
        for (const json& r : it.value()) {
          require(r.is_array() && r.size() == 2 && r[0].is_string() && r[1].is_number(), w,
                  "each rotation is [axis, degrees]", R"(e.g. ["z", 90])");
          const double deg = r[1].get<double>();
          require(std::isfinite(deg), w, "angle not finite", "give degrees");
          Affine rot = Affine::Identity();
          rot.linear() = axis_rotation(parse_axis(r[0].get<std::string>(), w), deg);
          p[jt] = p[jt] * rot;
        }
      }
    }
    keys.emplace_back(frame, std::move(p));
  }
  std::vector<Pose> out;
  out.push_back(keys[0].second);
  for (std::size_t k = 1; k < keys.size(); ++k) {
    const int n = keys[k].first - keys[k - 1].first;
    for (int f = 1; f <= n; ++f)
      out.push_back(interpolate(keys[k - 1].second, keys[k].second, double(f) / n));
  }
  return out;
}

std::vector<Pose> pose_script_animation(const Rig& rig, const std::string& path) {
  std::ifstream in(path);
  require(bool(in), path, "cannot be read", "check the pose script path");
  std::stringstream ss;
  ss << in.rdbuf();
  return pose_script_from_json(rig, ss.str(), path);
}

}  // namespace isokit::skinning
