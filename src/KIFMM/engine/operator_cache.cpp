// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "operator_cache.h"

#include "m2l_fft.h"
#include "surface.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace kifmm {

namespace {

constexpr char kMagic[8] = {'K', 'I', 'F', 'M', 'M', 'O', 'P', 'S'};

struct Fnv {
  uint64_t h = 1469598103934665603ULL;
  void add(const void *p, std::size_t n)
  {
    const unsigned char *c = (const unsigned char *) p;
    for (std::size_t i = 0; i < n; ++i) {
      h ^= c[i];
      h *= 1099511628211ULL;
    }
  }
};

std::mutex &cache_mutex()
{
  static std::mutex m;
  return m;
}
struct Entry {
  std::shared_ptr<const OperatorSet> op;
  unsigned long last_use = 0;
};
std::map<std::pair<std::string, int>, Entry> &memory_cache()
{
  static std::map<std::pair<std::string, int>, Entry> c;
  return c;
}
unsigned long g_clock = 0;
constexpr std::size_t kMemoryBudget = std::size_t(1) << 30;    // bytes kept by the cache itself

// Drop least recently used sets while over budget (evaluators keep theirs alive).
void evict()
{
  auto &mc = memory_cache();
  std::size_t total = 0;
  for (auto &e : mc) total += e.second.op->bytes();
  while (total > kMemoryBudget && mc.size() > 1) {
    auto oldest = mc.begin();
    for (auto it = mc.begin(); it != mc.end(); ++it)
      if (it->second.last_use < oldest->second.last_use) oldest = it;
    total -= oldest->second.op->bytes();
    mc.erase(oldest);
  }
}

OperatorCacheCounters g_counters;

std::vector<std::vector<double> *> arrays(OperatorSet &op)
{
  std::vector<std::vector<double> *> a = {&op.uc2e_a, &op.uc2e_b, &op.dc2e_a, &op.dc2e_b};
  for (int i = 0; i < 8; ++i) a.push_back(&op.m2m[i]);
  for (int i = 0; i < 8; ++i) a.push_back(&op.l2l[i]);
  a.push_back(&op.m2l_hat);
  return a;
}

// Operators computed by builds with different compilers or instruction sets (FMA contraction,
// AVX-512, sanitizers) differ in the last bits. A run that loads another build's file gets a
// trajectory that differs in the last bits from one that computes its own, which chaotic
// dynamics amplify, and MPI ranks could even use different sets. So the file name carries a
// fingerprint of the build that computed it.
uint64_t build_fingerprint()
{
  Fnv h;
  const char *flags = __VERSION__
#if defined(__AVX512F__)
      " avx512f"
#endif
#if defined(__AVX2__)
      " avx2"
#endif
#if defined(__FMA__)
      " fma"
#endif
#if defined(__FAST_MATH__)
      " fast-math"
#endif
#if defined(__SANITIZE_ADDRESS__)
      " asan"
#endif
#if defined(__OPTIMIZE__)
      " opt"
#endif
      ;
  h.add(flags, std::strlen(flags));
  return h.h;
}

}    // namespace

std::string operator_cache_file(const std::string &cache_dir, const std::string &id, int p)
{
  std::string s;
  for (char c : id) {
    if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_') s += c;
    else if (c == '.') s += 'd';
    else if (c == '+') s += 'P';
    else if (c == '-') s += 'M';
    else {
      char b[8];
      std::snprintf(b, sizeof b, "x%02x", (unsigned char) c);
      s += b;
    }
  }
  char build[24];
  std::snprintf(build, sizeof build, "_b%08x", (unsigned) (build_fingerprint() & 0xffffffffu));
  return cache_dir + "/kifmm_ops_v" + std::to_string(kOperatorVersion) + "_" + s + "_p" + std::to_string(p) + build +
      ".bin";
}

bool write_operator_file(const std::string &path, const OperatorSet &op0)
{
  OperatorSet &op = const_cast<OperatorSet &>(op0);    // arrays() only reads here
  // unique per process and thread (several MPI ranks may write the same set at once)
  const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + "_" +
      std::to_string(std::hash<std::thread::id>()(std::this_thread::get_id()));
  std::ofstream f(tmp, std::ios::binary);
  if (!f) return false;
  Fnv h;
  auto put = [&](const void *p, std::size_t n) {
    f.write((const char *) p, (std::streamsize) n);
    h.add(p, n);
  };
  put(kMagic, 8);
  const int32_t hdr[5] = {kOperatorVersion, op.p, op.nsurf, op.rank, op.nfreq};
  put(hdr, sizeof hdr);
  const uint64_t idlen = op.id.size();
  put(&idlen, 8);
  put(op.id.data(), idlen);
  for (auto *a : arrays(op)) {
    const uint64_t n = a->size();
    put(&n, 8);
    put(a->data(), n * sizeof(double));
  }
  const uint64_t sum = h.h;
  f.write((const char *) &sum, 8);
  f.close();
  if (!f) {
    std::remove(tmp.c_str());
    return false;
  }
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}

std::shared_ptr<OperatorSet> read_operator_file(const std::string &path, const std::string &id, int p)
{
  std::ifstream f(path, std::ios::binary);
  if (!f) return nullptr;
  Fnv h;
  auto get = [&](void *d, std::size_t n) {
    f.read((char *) d, (std::streamsize) n);
    if (!f) return false;
    h.add(d, n);
    return true;
  };
  char magic[8];
  if (!get(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) return nullptr;
  int32_t hdr[5];
  if (!get(hdr, sizeof hdr)) return nullptr;
  if (hdr[0] != kOperatorVersion || hdr[1] != p || hdr[2] != surface_size(p) || hdr[4] != m2l_nfreq(p)) return nullptr;
  const int ns = hdr[2], rank = hdr[3], nfreq = hdr[4];
  if (rank <= 0 || rank > ns) return nullptr;
  uint64_t idlen;
  if (!get(&idlen, 8) || idlen != id.size()) return nullptr;
  std::string fid(idlen, '\0');
  if (!get(&fid[0], idlen) || fid != id) return nullptr;
  auto op = std::make_shared<OperatorSet>();
  op->p = p;
  op->nsurf = ns;
  op->rank = rank;
  op->nfreq = nfreq;
  op->id = id;
  const auto arr = arrays(*op);
  for (std::size_t i = 0; i < arr.size(); ++i) {
    uint64_t expect;
    if (i < 4) expect = (uint64_t) ns * rank;
    else if (i < 20) expect = (uint64_t) ns * ns;
    else expect = (uint64_t) kM2LKernels * 2 * nfreq;
    uint64_t n;
    if (!get(&n, 8) || n != expect) return nullptr;
    arr[i]->resize(n);
    if (!get(arr[i]->data(), n * sizeof(double))) return nullptr;
  }
  uint64_t sum;
  const uint64_t computed = h.h;
  f.read((char *) &sum, 8);
  if (!f || sum != computed) return nullptr;
  return op;
}

std::shared_ptr<const OperatorSet> get_operator_set(const UnitKernel &k, int p, const std::string &cache_dir,
                                                    double *t_setup)
{
  std::lock_guard<std::mutex> lock(cache_mutex());
  auto &mc = memory_cache();
  const auto key = std::make_pair(k.id, p);
  auto it = mc.find(key);
  if (it != mc.end()) {
    it->second.last_use = ++g_clock;
    return it->second.op;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::shared_ptr<OperatorSet> op;
  std::string path;
  if (!cache_dir.empty()) {
    path = operator_cache_file(cache_dir, k.id, p);
    op = read_operator_file(path, k.id, p);
    if (op) ++g_counters.disk_reads;
  }
  if (!op) {
    op = compute_operators(k, p);
    ++g_counters.computed;
    if (!path.empty() && write_operator_file(path, *op)) ++g_counters.disk_writes;    // best effort
  }
  mc[key] = Entry{op, ++g_clock};
  evict();
  if (t_setup) *t_setup += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return op;
}

OperatorCacheCounters operator_cache_counters()
{
  std::lock_guard<std::mutex> lock(cache_mutex());
  return g_counters;
}

void clear_operator_memory_cache()
{
  std::lock_guard<std::mutex> lock(cache_mutex());
  memory_cache().clear();
}

}    // namespace kifmm
