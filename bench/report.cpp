// SPDX-License-Identifier: MIT
// isokit-bench-report: reads Google Benchmark JSON files (run with repetitions) and prints, per
// benchmark, the median time, the spread (min..max over repetitions), the median throughput, and
// the ratio of its median time to a baseline benchmark's.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace {

struct Runs {
  std::vector<double> time_ms, items_per_s;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double to_ms(double t, const std::string& unit) {
  if (unit == "ns") return t * 1e-6;
  if (unit == "us") return t * 1e-3;
  if (unit == "s") return t * 1e3;
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"isokit-bench-report: ratio tables from Google Benchmark JSON"};
  std::vector<std::string> files;
  std::string baseline;
  app.add_option("files", files, "Google Benchmark --benchmark_out JSON files")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--baseline", baseline, "Benchmark name the ratios refer to (default: the first)");
  CLI11_PARSE(app, argc, argv);

  std::map<std::string, Runs> runs;
  std::vector<std::string> order;
  std::string context;
  for (const auto& path : files) {
    nlohmann::json j;
    try {
      std::ifstream in(path);
      in >> j;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "isokit-bench-report: '%s' is not Google Benchmark JSON (%s)\n", path.c_str(),
                   e.what());
      return 1;
    }
    if (!j.contains("benchmarks")) {
      std::fprintf(stderr,
                   "isokit-bench-report: '%s' has no \"benchmarks\" array; run with --benchmark_out\n",
                   path.c_str());
      return 1;
    }
    if (context.empty() && j.contains("context")) {
      const auto& c = j["context"];
      context = c.value("host_name", "?") + ", " + std::to_string(c.value("num_cpus", 0)) + " CPUs @ " +
                std::to_string(c.value("mhz_per_cpu", 0)) + " MHz, " + c.value("library_build_type", "?") +
                " benchmark lib";
    }
    for (const auto& b : j["benchmarks"]) {
      if (b.value("run_type", "iteration") != "iteration") continue;  // skip aggregates
      const std::string name = b.value("run_name", b.value("name", "?"));
      if (!runs.count(name)) order.push_back(name);
      Runs& r = runs[name];
      r.time_ms.push_back(to_ms(b.value("real_time", 0.0), b.value("time_unit", "ns")));
      if (b.contains("items_per_second")) r.items_per_s.push_back(b["items_per_second"].get<double>());
    }
  }
  if (order.empty()) {
    std::fprintf(stderr, "isokit-bench-report: no benchmark runs found\n");
    return 1;
  }
  if (baseline.empty()) baseline = order.front();
  if (!runs.count(baseline)) {
    std::fprintf(stderr, "isokit-bench-report: baseline '%s' not among the benchmarks\n", baseline.c_str());
    return 1;
  }
  const double base = median(runs[baseline].time_ms);
  std::printf("machine: %s\n", context.c_str());
  std::printf("%-28s %5s %12s %21s %14s %10s\n", "benchmark", "reps", "median ms", "spread ms (min..max)",
              "items/s", "time/base");
  for (const auto& name : order) {
    const Runs& r = runs[name];
    const auto [lo, hi] = std::minmax_element(r.time_ms.begin(), r.time_ms.end());
    const double med = median(r.time_ms);
    char items[32] = "-";
    if (!r.items_per_s.empty()) std::snprintf(items, sizeof items, "%.3gM", median(r.items_per_s) / 1e6);
    std::printf("%-28s %5zu %12.4f %10.4f..%-10.4f %14s %10.3f\n", name.c_str(), r.time_ms.size(), med, *lo,
                *hi, items, base > 0 ? med / base : 0.0);
  }
  return 0;
}
