// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Process-wide cache of operator sets, keyed by (unit kernel id, order), thread-safe (least
// recently used sets are dropped beyond 1 GiB; evaluators keep the sets they use), with an
// optional on-disk copy: <cache_dir>/kifmm_ops_v<version>_<id>_p<order>.bin. A file is used
// only if its header (magic, version, id, order, sizes) matches and its checksum is right;
// otherwise it is recomputed and rewritten (written to a temporary name, then renamed).
#pragma once

#include "operators.h"

#include <memory>
#include <string>

namespace kifmm {

// Returns the operators, computing them if needed; *t_setup (if given) is increased by the
// time spent computing or reading from disk in this call (0 on an in-memory hit).
std::shared_ptr<const OperatorSet> get_operator_set(const UnitKernel &k, int p,
                                                    const std::string &cache_dir, double *t_setup);

// Counters since process start (tests): operator sets computed, read from disk, written.
struct OperatorCacheCounters {
  long computed = 0, disk_reads = 0, disk_writes = 0;
};
OperatorCacheCounters operator_cache_counters();

// Drop the in-memory cache (tests; operators held by evaluators stay alive).
void clear_operator_memory_cache();

// File name used for (id, p) in cache_dir.
std::string operator_cache_file(const std::string &cache_dir, const std::string &id, int p);

// Disk I/O (exposed for tests): write returns false on failure; read returns null on any
// mismatch or corruption.
bool write_operator_file(const std::string &path, const OperatorSet &op);
std::shared_ptr<OperatorSet> read_operator_file(const std::string &path, const std::string &id, int p);

}    // namespace kifmm
