// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// 64-bit Morton keys: 21 bits per axis interleaved (x in the lowest bit of each triple).
// A cell at level l is identified by the pair (level, prefix) where prefix = key >> 3(21-l);
// level_key() packs both into one 64-bit value with a leading 1 bit (1 << 3l) | prefix, the
// form used to name cells across processes (MPI partition by key ranges).
#pragma once

#include <cstdint>

namespace kifmm {

constexpr int kMortonBits = 21;    // levels 0..21

inline uint64_t morton_spread(uint64_t v)
{
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

inline uint32_t morton_compact(uint64_t v)
{
  v &= 0x1249249249249249ULL;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ULL;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00fULL;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffULL;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffULL;
  v = (v ^ (v >> 32)) & 0x1fffffULL;
  return (uint32_t) v;
}

inline uint64_t morton_encode(uint32_t ix, uint32_t iy, uint32_t iz)
{
  return morton_spread(ix) | (morton_spread(iy) << 1) | (morton_spread(iz) << 2);
}

inline void morton_decode(uint64_t key, uint32_t &ix, uint32_t &iy, uint32_t &iz)
{
  ix = morton_compact(key);
  iy = morton_compact(key >> 1);
  iz = morton_compact(key >> 2);
}

inline uint64_t level_key(int level, uint64_t prefix) { return (uint64_t(1) << (3 * level)) | prefix; }

}    // namespace kifmm
