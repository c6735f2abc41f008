// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "style_maps.h"

#include "comm.h"
#include "compute.h"
#include "domain.h"
#include "error.h"
#include "fix.h"
#include "force.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "utils.h"

#include <cstring>

using namespace LAMMPS_NS;

namespace kifmm_lammps {

namespace {
template <typename Map, typename Creator>
void put(LAMMPS *lmp, Map *map, const lammpsplugin_t &style, Creator creator,
         bool warn_override)
{
  if (warn_override && map->find(style.name) != map->end() && lmp->comm && lmp->comm->me == 0)
    lmp->error->warning(FLERR, "Overriding existing {} style {} with the plugin's version",
                        style.style, style.name);
  (*map)[style.name] = creator;
}

// index of the first fix or compute of style `name`, -1 if none
template <typename T> int first_of_style(T **list, int n, const std::string &name)
{
  for (int i = 0; i < n; ++i)
    if (name == list[i]->style) return i;
  return -1;
}
}    // namespace

bool is_known_style_kind(const std::string &k)
{
  return k == "pair" || k == "bond" || k == "angle" || k == "dihedral" || k == "improper" ||
      k == "kspace" || k == "fix" || k == "compute" || k == "region" || k == "command";
}

bool add_style_to_maps(LAMMPS *lmp, const lammpsplugin_t &s, bool warn)
{
  const std::string kind = s.style;
  if (kind == "pair")
    put(lmp, lmp->force->pair_map, s, (Force::PairCreator) s.creator.v1, warn);
  else if (kind == "bond")
    put(lmp, lmp->force->bond_map, s, (Force::BondCreator) s.creator.v1, warn);
  else if (kind == "angle")
    put(lmp, lmp->force->angle_map, s, (Force::AngleCreator) s.creator.v1, warn);
  else if (kind == "dihedral")
    put(lmp, lmp->force->dihedral_map, s, (Force::DihedralCreator) s.creator.v1, warn);
  else if (kind == "improper")
    put(lmp, lmp->force->improper_map, s, (Force::ImproperCreator) s.creator.v1, warn);
  else if (kind == "kspace")
    put(lmp, lmp->force->kspace_map, s, (Force::KSpaceCreator) s.creator.v1, warn);
  else if (kind == "fix")
    put(lmp, lmp->modify->fix_map, s, (Modify::FixCreator) s.creator.v2, warn);
  else if (kind == "compute")
    put(lmp, lmp->modify->compute_map, s, (Modify::ComputeCreator) s.creator.v2, warn);
  else if (kind == "region")
    put(lmp, lmp->domain->region_map, s, (Domain::RegionCreator) s.creator.v2, warn);
  else if (kind == "command")
    put(lmp, lmp->input->command_map, s, (Input::CommandCreator) s.creator.v1, warn);
  else {
    if (lmp->comm && lmp->comm->me == 0)
      lmp->error->warning(FLERR, "Plugin style {} has unsupported style kind {}: ignored",
                          s.name, kind);
    return false;
  }
  return true;
}

bool remove_style_from_maps(LAMMPS *lmp, const std::string &kind, const std::string &name)
{
  auto drop = [&](auto *map) {
    auto it = map->find(name);
    if (it != map->end()) map->erase(it);
  };
  Force *force = lmp->force;
  Modify *modify = lmp->modify;
  if (kind == "pair") {
    drop(force->pair_map);
    if (force->pair_style) {
      if (utils::strmatch(force->pair_style, "^hybrid")) {
        if (force->pair_match(name, 1, 1) != nullptr) force->create_pair("none", 0);
      } else if (name == force->pair_style)
        force->create_pair("none", 0);
    }
  } else if (kind == "bond") {
    drop(force->bond_map);
  } else if (kind == "angle") {
    drop(force->angle_map);
  } else if (kind == "dihedral") {
    drop(force->dihedral_map);
  } else if (kind == "improper") {
    drop(force->improper_map);
  } else if (kind == "kspace") {
    drop(force->kspace_map);
    if (force->kspace_style && name == force->kspace_style) force->create_kspace("none", 0);
  } else if (kind == "fix") {
    drop(modify->fix_map);
    // (deleting a fix may delete others: search again after each)
    for (int i = first_of_style(modify->fix, modify->nfix, name); i >= 0;
         i = first_of_style(modify->fix, modify->nfix, name))
      modify->delete_fix(i);
  } else if (kind == "compute") {
    drop(modify->compute_map);
    for (int i = first_of_style(modify->compute, modify->ncompute, name); i >= 0;
         i = first_of_style(modify->compute, modify->ncompute, name))
      modify->delete_compute(i);
  } else if (kind == "region") {
    drop(lmp->domain->region_map);
  } else if (kind == "command") {
    drop(lmp->input->command_map);
  } else
    return false;
  return true;
}

}    // namespace kifmm_lammps
