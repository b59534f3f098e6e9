// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

#include "isokit/core/error.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/io.h"
#include "isokit/operators/profile.h"

using namespace isokit;
using namespace isokit::operators;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("isokit-test-formats-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

void write_text(const fs::path& p, const std::string& s) {
  std::ofstream(p, std::ios::binary) << s;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void replace(std::string& s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  s.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("spec JSON round trip is exact for every preset and a custom controller", "[operators][formats]") {
  for (const auto& name : preset_spec_names()) {
    const OperatorSpec s = preset_spec(name, 40);
    CHECK(spec_from_json(spec_to_json(s), "mem") == s);
  }
  OperatorSpec s = preset_spec("bulge", 16);
  s.controller = "mine";
  s.controller_knots = {{0, 0}, {0.123456789012345, 0.3}, {kPi, 1}};
  s.distance_slope = 0.7;
  CHECK(spec_from_json(spec_to_json(s), "mem") == s);
}

TEST_CASE("spec -> npy -> load round trip is exact", "[operators][formats]") {
  const OperatorSpec spec = preset_spec("contact", 16);
  const GridOperator g = generate_operator(spec);
  const fs::path npy = scratch("op.npy");
  save_operator(npy.string(), spec, g);
  CHECK(fs::exists(scratch("op.json")));
  const StoredOperator back = load_operator(npy.string());
  CHECK(back.spec == spec);
  CHECK(back.grid.nd() == g.nd());
  CHECK(back.grid.nf() == g.nf());
  CHECK(back.grid.data() == g.data());  // bit-exact float32
  // NumPy header: magic, version 1.0, 64-byte aligned data, shape (nd, nf, nf).
  const std::string bytes = read_text(npy);
  CHECK(bytes.compare(0, 6, "\x93NUMPY") == 0);
  const std::size_t hlen = static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  CHECK((10 + hlen) % 64 == 0);
  CHECK(bytes.find("'shape': (16, 16, 16)") != std::string::npos);
  CHECK(bytes.size() == 10 + hlen + 16 * 16 * 16 * 4);
  // No temporary files left behind.
  for (const auto& e : fs::directory_iterator(npy.parent_path()))
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
}

TEST_CASE("bad specs: errors name the file and the field", "[operators][formats]") {
  const std::string good = spec_to_json(preset_spec("contact", 16));
  auto err = [](const std::string& text) {
    try {
      spec_from_json(text, "S.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(err("{ not json"), Catch::Contains("S.json") && Catch::Contains("not valid JSON"));
  std::string s = good;
  replace(s, "\"version\": 1", "\"version\": 2");
  CHECK_THAT(err(s), Catch::Contains("S.json: version") && Catch::Contains("unsupported version 2"));
  s = good;
  replace(s, "isokit-operator-spec", "something-else");
  CHECK_THAT(err(s), Catch::Contains("S.json: format"));
  s = good;
  replace(s, "\"resolution\": 16", "\"resolution\": 7");
  CHECK_THAT(err(s), Catch::Contains("S.json: resolution"));
  s = good;
  replace(s, "\"resolution\": 16", "\"resolution\": 2000");
  CHECK_THAT(err(s), Catch::Contains("S.json: resolution"));
  s = good;
  replace(s, "\"resolution\": 16", "\"resolution\": \"big\"");
  CHECK_THAT(err(s), Catch::Contains("S.json: resolution") && Catch::Contains("integer"));
  s = good;
  replace(s, "\"curves\"", "\"kurves\"");
  CHECK_THAT(err(s), Catch::Contains("S.json: spec.curves") && Catch::Contains("missing"));

  OperatorSpec spec = preset_spec("contact", 16);
  spec.curves[0].keyframes[0].points[1] = {1.2, 0.5};
  CHECK_THAT(err(spec_to_json(spec)), Catch::Contains("S.json: curves[0].keyframes[0].points[1]") &&
                                          Catch::Contains("outside the unit square"));
  spec = preset_spec("contact", 16);
  spec.curves[1].keyframes[1].points[1] = {1.0, 1.0};
  CHECK_THAT(err(spec_to_json(spec)),
             Catch::Contains("S.json: curves[1].keyframes[1].points[1]") && Catch::Contains("g = 1"));
  spec = preset_spec("contact", 16);
  spec.curves[0].keyframes[0].points[0] = {0.0, 0.6};
  CHECK_THAT(err(spec_to_json(spec)),
             Catch::Contains("S.json: curves[0].keyframes[0].points[0]") && Catch::Contains("axis"));
  spec = preset_spec("contact", 16);
  spec.curves.clear();
  CHECK_THAT(err(spec_to_json(spec)), Catch::Contains("S.json: curves") && Catch::Contains("empty"));
  spec = preset_spec("contact", 16);
  spec.curves[0].keyframes[0].points = {{0, 0.5}, {0.6, 0.5}, {0.6, 0.2}, {0.3, 0.6}};
  CHECK_THAT(err(spec_to_json(spec)),
             Catch::Contains("S.json: curves[0]") && Catch::Contains("self-intersects"));
  spec = preset_spec("contact", 16);
  spec.curves[0].keyframes[0].points = {{0.3, 0.3}};
  CHECK_THAT(err(spec_to_json(spec)),
             Catch::Contains("curves[0].keyframes[0].points") && Catch::Contains("at least 2"));
  spec = preset_spec("contact", 16);
  spec.curves.erase(spec.curves.begin());
  CHECK_THAT(err(spec_to_json(spec)), Catch::Contains("no curve of kind \"boundary\""));
  spec = preset_spec("bulge", 16);
  spec.curves[0].keyframes[1].points.pop_back();
  CHECK_THAT(err(spec_to_json(spec)),
             Catch::Contains("curves[0].keyframes[1].points") && Catch::Contains("same number"));
  CHECK_THROWS_WITH(load_spec(scratch("missing.json").string()), Catch::Contains("missing.json"));
}

TEST_CASE("bad .npy files: truncated, wrong dtype, shape mismatch, missing spec", "[operators][formats]") {
  const OperatorSpec spec = preset_spec("clean-union", 12);
  const GridOperator g = generate_operator(spec);
  const fs::path npy = scratch("bad.npy");
  save_operator(npy.string(), spec, g);
  const std::string bytes = read_text(npy);
  write_text(npy, bytes.substr(0, bytes.size() - 7));
  CHECK_THROWS_WITH(load_operator(npy.string()),
                    Catch::Contains("bad.npy: data") && Catch::Contains("truncated"));
  write_text(npy, bytes.substr(0, 40));
  CHECK_THROWS_WITH(load_operator(npy.string()), Catch::Contains("bad.npy"));
  std::string wrong = bytes;
  replace(wrong, "'<f4'", "'<f8'");
  write_text(npy, wrong);
  CHECK_THROWS_WITH(load_operator(npy.string()), Catch::Contains("bad.npy: dtype"));
  write_text(npy, "hello");
  CHECK_THROWS_WITH(load_operator(npy.string()), Catch::Contains("bad.npy: magic"));
  // A valid .npy whose shape disagrees with the spec beside it.
  const OperatorSpec other = preset_spec("clean-union", 10);
  write_npy_f32(npy.string(), generate_operator(other).data().data(), 10, 10, 10);
  CHECK_THROWS_WITH(load_operator(npy.string()),
                    Catch::Contains("bad.npy: shape") && Catch::Contains("bad.json"));
  fs::remove(scratch("bad.json"));
  CHECK_THROWS_WITH(load_operator(npy.string()), Catch::Contains("bad.json"));
  // A grid that does not match the spec is not saved, and nothing is written.
  const fs::path never = scratch("never.npy");
  CHECK_THROWS_AS(save_operator(never.string(), spec, generate_operator(other)), InputError);
  CHECK_FALSE(fs::exists(never));
  CHECK_FALSE(fs::exists(scratch("never.json")));
  CHECK_THROWS(save_operator((scratch("no-such-dir") / "x.npy").string(), spec, g));
}

TEST_CASE("profile geometry: signed distance sides, self-intersection", "[operators][formats]") {
  const std::vector<Point2> l{{0, 0.5}, {0.5, 0.5}, {0.5, 0}};
  CHECK(signed_distance(l, {0.25, 0.75}) == Approx(0.25));
  CHECK(signed_distance(l, {0.25, 0.25}) == Approx(-0.25));
  CHECK(signed_distance(l, {0.75, 0.75}) == Approx(std::sqrt(0.125)));  // corner: pseudo-normal side
  CHECK(signed_distance(l, {0.4, 0.4}) == Approx(-0.1));
  CHECK_FALSE(self_intersects(l));
  CHECK(self_intersects({{0, 0}, {1, 1}, {1, 0}, {0, 1}}));
  CHECK(self_intersects({{0, 0}, {1, 0}, {0.5, 0}}));  // folds back on itself
  const SliceProfile p(preset_spec("contact", 16), 0.0);
  CHECK(p.polylines().size() == 1);  // the zero-length contact line is dropped at d = 0
  CHECK(p.constraint_distance({0.75, 0.75}) > 0);
  const SliceProfile q(preset_spec("contact", 16), 1.0);
  CHECK(q.polylines().size() == 2);
  CHECK(q.constraint_distance({0.7, 0.72}) == Approx(0.02 / std::sqrt(2.0)));  // contact: unsigned
  CHECK(q.constraint_distance({0.72, 0.7}) == Approx(0.02 / std::sqrt(2.0)));
}
