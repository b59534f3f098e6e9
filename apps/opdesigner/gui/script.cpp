// SPDX-License-Identifier: MIT
#include "isokit/studio/script.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "isokit/core/error.h"

namespace isokit::studio {
namespace {

using nlohmann::json;

struct Context {
  const std::string& source;
  std::size_t event;
  std::string where() const { return source + ", event " + std::to_string(event); }
};

plot::Point2 pair_of(const json& j, const Context& c, const std::string& field) {
  require(j.is_array() && j.size() == 2 && j[0].is_number() && j[1].is_number(), c.where(),
          "field '" + field + "' is not a pair of numbers", "write e.g. [0.4, 0.25]");
  return {j[0].get<double>(), j[1].get<double>()};
}

ScriptTarget target_of(const json& j, const Context& c) {
  require(j.is_object() && j.size() == 1, c.where(), "'to' must be an object with one key",
          "use {\"px\": [x, y]}, {\"op\": [f1, f2]}, {\"point\": [curve, index]}, {\"knot\": i}, "
          "{\"ctrl\": [alpha, d]} or {\"preview\": [x, y]}");
  ScriptTarget t;
  const auto it = j.begin();
  const std::string key = it.key();
  const json& value = it.value();
  if (key == "px" || key == "op" || key == "ctrl" || key == "preview") {
    t.kind = key == "px"     ? TargetKind::kPixel
             : key == "op"   ? TargetKind::kOperator
             : key == "ctrl" ? TargetKind::kController
                             : TargetKind::kPreview;
    t.at = pair_of(value, c, key);
  } else if (key == "point") {
    const plot::Point2 p = pair_of(value, c, key);
    t.kind = TargetKind::kControlPoint;
    t.curve = int(p[0]);
    t.index = int(p[1]);
  } else if (key == "knot") {
    require(value.is_number_integer(), c.where(), "'knot' is not an integer", "give the knot's index");
    t.kind = TargetKind::kKnot;
    t.index = value.get<int>();
  } else {
    require(false, c.where(), "unknown target '" + key + "'", "use px, op, point, knot, ctrl or preview");
  }
  return t;
}

int int_field(const json& e, const char* name, int fallback, int lo, const Context& c) {
  if (!e.contains(name)) return fallback;
  require(e[name].is_number_integer() && e[name].get<int>() >= lo, c.where(),
          std::string("field '") + name + "' is not an integer >= " + std::to_string(lo), "fix the number");
  return e[name].get<int>();
}

std::optional<double> number_field(const json& e, const char* name, const Context& c) {
  if (!e.contains(name)) return std::nullopt;
  require(e[name].is_number(), c.where(), std::string("field '") + name + "' is not a number", "fix it");
  return e[name].get<double>();
}

std::string string_field(const json& e, const char* name, const Context& c) {
  require(e.contains(name) && e[name].is_string() && !e[name].get<std::string>().empty(), c.where(),
          std::string("needs a non-empty string '") + name + "'", "add it");
  return e[name].get<std::string>();
}

ScriptEvent event_of(const json& e, const Context& c) {
  require(e.is_object() && e.contains("type") && e["type"].is_string(), c.where(),
          "is not an object with a string 'type'", "e.g. {\"type\": \"frames\", \"n\": 3}");
  const std::string type = e["type"].get<std::string>();
  ScriptEvent ev;
  if (type == "move") {
    ev.kind = EventKind::kMove;
    require(e.contains("to"), c.where(), "a move needs 'to'", "add {\"to\": {\"op\": [f1, f2]}}");
    ev.target = target_of(e["to"], c);
    ev.frames = int_field(e, "frames", 1, 1, c);
  } else if (type == "press" || type == "release") {
    ev.kind = type == "press" ? EventKind::kPress : EventKind::kRelease;
    ev.button = int_field(e, "button", 0, 0, c);
    require(ev.button <= 2, c.where(), "button must be 0, 1 or 2", "0 = left");
  } else if (type == "key") {
    ev.kind = EventKind::kKey;
    ev.key = string_field(e, "key", c);
    ev.ctrl = e.value("ctrl", false);
    ev.shift = e.value("shift", false);
  } else if (type == "frames") {
    ev.kind = EventKind::kFrames;
    ev.frames = int_field(e, "n", 1, 0, c);
  } else if (type == "wait_solved") {
    ev.kind = EventKind::kWaitSolved;
    ev.frames = int_field(e, "max_frames", 600, 1, c);
  } else if (type == "screenshot" || type == "mark") {
    ev.kind = type == "screenshot" ? EventKind::kScreenshot : EventKind::kMark;
    ev.name = string_field(e, "name", c);
    require(ev.name.find('/') == std::string::npos, c.where(), "name '" + ev.name + "' contains '/'",
            "give a plain name; the folder is --screenshot-dir");
  } else if (type == "set") {
    ev.kind = EventKind::kSet;
    ev.d = number_field(e, "d", c);
    ev.angle = number_field(e, "angle", c);
  } else {
    require(false, c.where(), "unknown type '" + type + "'",
            "use move, press, release, key, frames, wait_solved, screenshot, set or mark");
  }
  return ev;
}

}  // namespace

std::vector<ScriptEvent> parse_script(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    require(false, source, std::string("is not valid JSON (") + e.what() + ")", "fix the syntax");
  }
  require(j.is_array(), source, "is not a JSON list of events",
          "write [{\"type\": \"frames\", \"n\": 1}, ...]");
  std::vector<ScriptEvent> out;
  for (std::size_t i = 0; i < j.size(); ++i) out.push_back(event_of(j[i], Context{source, i + 1}));
  return out;
}

std::vector<ScriptEvent> load_script(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "script file '" + path + "'", "cannot be read", "check the path");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_script(ss.str(), "script file '" + path + "'");
}

}  // namespace isokit::studio
