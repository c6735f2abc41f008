// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The problem every driver of the anchor benchmark solves, read from one binary file written by
// anchors_points: n points (xyz interleaved) with charges q, sources = targets, and the exact
// Laplace gradient (G = 1/r, direct double-precision sum, r = 0 excluded) at a random sample of
// the points. Also the drivers' common pieces: command line, clocks, error, result rows.
// Header only and free of the engine, so that the drivers of other codes include nothing else.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace anchors {

struct Problem {
  std::string set;                    // point set name (uniform, plummer)
  std::uint64_t n = 0;
  std::vector<double> xyz, q;         // 3n, n
  std::vector<std::uint64_t> sample;  // sampled target indices
  std::vector<double> ref_grad;       // 3 per sampled target, in the order of sample
};

constexpr std::uint64_t kMagic = 0x31504d4641534e41ull;    // "ANSAFMP1"

inline void write_problem(const std::string &path, const Problem &p)
{
  FILE *f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  char name[32] = {0};
  std::strncpy(name, p.set.c_str(), sizeof(name) - 1);
  const std::uint64_t ns = p.sample.size();
  bool ok = std::fwrite(&kMagic, 8, 1, f) == 1 && std::fwrite(name, 1, 32, f) == 32 &&
            std::fwrite(&p.n, 8, 1, f) == 1 && std::fwrite(&ns, 8, 1, f) == 1 &&
            std::fwrite(p.xyz.data(), 8, 3 * p.n, f) == 3 * p.n && std::fwrite(p.q.data(), 8, p.n, f) == p.n &&
            std::fwrite(p.sample.data(), 8, ns, f) == ns && std::fwrite(p.ref_grad.data(), 8, 3 * ns, f) == 3 * ns;
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) throw std::runtime_error("cannot write " + path);
}

inline Problem read_problem(const std::string &path)
{
  FILE *f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot read " + path);
  Problem p;
  std::uint64_t magic = 0, ns = 0;
  char name[32] = {0};
  bool ok = std::fread(&magic, 8, 1, f) == 1 && magic == kMagic && std::fread(name, 1, 32, f) == 32 &&
            std::fread(&p.n, 8, 1, f) == 1 && std::fread(&ns, 8, 1, f) == 1;
  if (ok) {
    name[31] = 0;
    p.set = name;
    p.xyz.resize(3 * p.n);
    p.q.resize(p.n);
    p.sample.resize(ns);
    p.ref_grad.resize(3 * ns);
    ok = std::fread(p.xyz.data(), 8, 3 * p.n, f) == 3 * p.n && std::fread(p.q.data(), 8, p.n, f) == p.n &&
         std::fread(p.sample.data(), 8, ns, f) == ns && std::fread(p.ref_grad.data(), 8, 3 * ns, f) == 3 * ns;
  }
  std::fclose(f);
  if (!ok) throw std::runtime_error("not a problem file of anchors_points: " + path);
  return p;
}

// Relative RMS gradient error over the sampled targets: sqrt(sum |s g_i - g_i^ref|^2 / sum
// |g_i^ref|^2), g (3 per point, all points in the input order) scaled by s to the convention of
// the reference (G = 1/r, gradient of the potential).
inline double gradient_error(const Problem &p, const double *grad, double scale)
{
  double num = 0, den = 0;
  for (std::size_t i = 0; i < p.sample.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      const double a = scale * grad[3 * p.sample[i] + d], b = p.ref_grad[3 * i + d];
      num += (a - b) * (a - b);
      den += b * b;
    }
  return std::sqrt(num / den);
}

// CPU time of the process (all its threads) and wall time, seconds.
struct Clock {
  double cpu, wall;
  static Clock now()
  {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    return {t.tv_sec + 1e-9 * t.tv_nsec, w};
  }
  Clock operator-(const Clock &o) const { return {cpu - o.cpu, wall - o.wall}; }
  Clock operator+(const Clock &o) const { return {cpu + o.cpu, wall + o.wall}; }
};

// The time the benchmark compares (ANCHORS_TIME, set by run.sh): CPU time unless "wall"
inline bool compare_cpu()
{
  const char *e = std::getenv("ANCHORS_TIME");
  return !e || std::strcmp(e, "wall") != 0;
}

// Command line of a driver: PROBLEM_FILE [--settings A:B,C:D,...] [--reps R] [--warmup W] [--cache DIR]
struct Args {
  std::string file, cache;
  std::vector<std::pair<double, double>> settings;    // (order or accuracy, leaf size; 0 = automatic)
  int reps = 1, warmup = 1;
};

inline std::vector<std::pair<double, double>> parse_settings(const std::string &s)
{
  std::vector<std::pair<double, double>> out;
  std::size_t pos = 0;
  while (pos < s.size()) {
    std::size_t end = s.find(',', pos);
    if (end == std::string::npos) end = s.size();
    const std::string item = s.substr(pos, end - pos);
    const std::size_t colon = item.find(':');
    out.emplace_back(std::stod(item.substr(0, colon)), colon == std::string::npos ? 0.0 : std::stod(item.substr(colon + 1)));
    pos = end + 1;
  }
  return out;
}

inline Args parse_args(int argc, char **argv, const char *usage)
{
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: %s needs a value\nusage: %s %s\n", argv[0], s.c_str(), argv[0], usage);
        std::exit(2);
      }
      return argv[++i];
    };
    if (s == "--settings")
      a.settings = parse_settings(value());
    else if (s == "--reps")
      a.reps = std::stoi(value());
    else if (s == "--warmup")
      a.warmup = std::stoi(value());
    else if (s == "--cache")
      a.cache = value();
    else if (!s.empty() && s[0] != '-' && a.file.empty())
      a.file = s;
    else {
      std::fprintf(stderr, "usage: %s %s\n", argv[0], usage);
      std::exit(2);
    }
  }
  if (a.file.empty() || a.settings.empty()) {
    std::fprintf(stderr, "usage: %s %s\n", argv[0], usage);
    std::exit(2);
  }
  return a;
}

// One result row, parsed by table.py: "ROW key=value ...".
inline void print_row(const char *code, const Problem &p, const std::string &setting, int order, int leaf,
                      int depth, double err, const Clock &t, const std::string &extra = "")
{
  std::printf("ROW code=%s set=%s n=%llu setting=%s order=%d leaf=%d depth=%d err=%.3e cpu=%.4f wall=%.4f%s%s\n",
              code, p.set.c_str(), (unsigned long long) p.n, setting.c_str(), order, leaf, depth, err, t.cpu,
              t.wall, extra.empty() ? "" : " ", extra.c_str());
  std::fflush(stdout);
}

}    // namespace anchors
