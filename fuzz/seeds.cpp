// SPDX-License-Identifier: MIT
// The seed inputs of the fuzz targets, written with the project's own writers (seeds.h).
#include "seeds.h"

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include "isokit/operators/io.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/setup.h"

namespace isokit::fuzz {

namespace fs = std::filesystem;

using namespace isokit::skinning;

namespace {

// A square tube along +y (rings at y = 0, 1, 2, capped), two joints at y = 0 and y = 1, blended
// weights on the middle ring, and a clip bending the child joint about z.
Rig two_joint_tube() {
  Rig rig;
  rig.name = "fuzz-seed-tube";
  const float c[4][2] = {{-0.3f, -0.3f}, {0.3f, -0.3f}, {0.3f, 0.3f}, {-0.3f, 0.3f}};
  rig.rest.resize(12, 3);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) rig.rest.row(4 * r + k) << c[k][0], float(r), c[k][1];
  rig.triangles.resize(20, 3);
  int t = 0;
  for (int r = 0; r < 2; ++r)
    for (int k = 0; k < 4; ++k) {
      const int a = 4 * r + k, b = 4 * r + (k + 1) % 4;
      rig.triangles.row(t++) << a, b + 4, b;
      rig.triangles.row(t++) << a, a + 4, b + 4;
    }
  rig.triangles.row(t++) << 0, 1, 2;
  rig.triangles.row(t++) << 0, 2, 3;
  rig.triangles.row(t++) << 8, 10, 9;
  rig.triangles.row(t++) << 8, 11, 10;
  const Affine up(Eigen::Translation3d(0, 1, 0));
  rig.joints = {Joint("root"), Joint("child", 0, up, up.inverse())};
  for (int v = 0; v < 12; ++v) {
    rig.weights.offsets.push_back(static_cast<int>(rig.weights.joints.size()));
    const int ring = v / 4;
    if (ring != 2) rig.weights.joints.push_back(0), rig.weights.weights.push_back(ring == 0 ? 1.0f : 0.5f);
    if (ring != 0) rig.weights.joints.push_back(1), rig.weights.weights.push_back(ring == 2 ? 1.0f : 0.5f);
  }
  rig.weights.offsets.push_back(static_cast<int>(rig.weights.joints.size()));
  Clip clip;
  clip.name = "bend";
  for (int f = 0; f < 3; ++f)
    clip.local.push_back({Affine::Identity(), up * Eigen::AngleAxisd(0.5 * f, Eigen::Vector3d::UnitZ())});
  rig.clips.push_back(clip);
  return rig;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

void export_with_assimp(const fs::path& glb, const fs::path& out, const char* format) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(glb.string(), 0);
  Assimp::Exporter exporter;
  if (!scene || exporter.Export(scene, format, out.string()) != AI_SUCCESS)
    throw std::runtime_error("assimp could not export " + out.string() + " (" + format + ")");
}

const char* kSetupExample = R"({ "version": 1,
  "tree": "2014",
  "default_operator": "contact",
  "joints": { "child": { "operator": "bulge", "relaxation": 0.5 } },
  "fit": { "samples": 50, "cull_h": 0.05, "grid_resolution": 32, "seed": 1, "opening_offset": 0.1 },
  "operators": { "resolution": 128, "slices": 128 },
  "tracker": { "max_iterations": 100, "tolerance": 1e-5, "sigma": 1.0, "contact_angle_deg": 55,
               "initial_newton_steps": 10, "smoothing_steps": 5, "beta_diffusion_steps": 3,
               "relaxation": "jacobi" },
  "projector": { "sigma": 0.35, "max_iterations": 50, "contact_angle_deg": 55 },
  "substeps": { "paper_rule": true, "fold_rule": true, "min_step_rad": 0.05, "max_step_rad": 0 } }
)";

void write_operator_seeds(const fs::path& out) {
  fs::create_directories(out / "spec");
  fs::create_directories(out / "npy");
  for (const std::string& name : isokit::operators::preset_spec_names())
    write_text(out / "spec" / (name + ".json"),
               isokit::operators::spec_to_json(isokit::operators::preset_spec(name, 16)));
  isokit::operators::OperatorSpec spec = isokit::operators::preset_spec("contact", 8);
  spec.slices = 8;
  std::vector<float> g(8 * 8 * 8);
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = static_cast<float>(i % 8) / 7.0f;
  isokit::operators::save_operator((out / "npy" / "op.npy").string(), spec,
                                   isokit::operators::GridOperator(8, 8, g));
  fs::remove(out / "npy" / "op.json");  // the npy target writes its own spec; only the .npy seeds
}

}  // namespace

void write_seeds(const fs::path& out) {
  for (const char* d : {"glb", "gltf", "dae", "fbx", "setup"}) fs::create_directories(out / d);
  const Rig rig = two_joint_tube();
  save_rig(rig, (out / "glb" / "tube.glb").string());
  save_rig(rig, (out / "gltf" / "tube.gltf").string());
  // assimp's COLLADA exporter writes animations that its importer cannot resolve: the .dae
  // seed is the rig without its clip.
  Rig still = rig;
  still.clips.clear();
  save_rig(still, (out / "glb" / "tube_still.glb").string());
  export_with_assimp(out / "glb" / "tube_still.glb", out / "dae" / "tube.dae", "collada");
  export_with_assimp(out / "glb" / "tube.glb", out / "fbx" / "tube.fbx", "fbx");
  export_with_assimp(out / "glb" / "tube.glb", out / "fbx" / "tube_ascii.fbx", "fbxa");
  setup_from_json(kSetupExample, "seed");
  write_text(out / "setup" / "example.json", kSetupExample);
  write_text(out / "setup" / "empty.json", "{}");
  write_operator_seeds(out);
}

}  // namespace isokit::fuzz
