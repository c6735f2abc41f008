// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// kspace_style kifmm: the full long-range sum (no real-space split) by the KIFMM engine.
// Kernels: coulomb (atom q, qqrd2e), gravity (mass, G, attractive), yukawa (screened coulomb
// as pair coul/debye); point dipoles with open boundaries (kspace_kifmm_dipoles.cpp). Open
// boundaries, or periodic ones (kspace_kifmm_periodic.cpp). Thin adapter: collects the atoms of nonzero strength,
// calls kifmm::Evaluator, scatters forces, energy and virial. See doc/kspace_kifmm.rst.
// MPI: on more than one rank the engine's distributed evaluation (each rank passes its own
// atoms; no all-gather), open or periodic boundaries.
#pragma once

#include "communicator.h"
#include "kifmm.h"
#include "kifmm_keywords.h"
#include "kifmm_timing.h"
#include "kspace.h"

#include <memory>
#include <string>
#include <vector>

namespace LAMMPS_NS {

class KSpaceKIFMM : public KSpace {
 public:
  KSpaceKIFMM(class LAMMPS *);
  ~KSpaceKIFMM() override;
  void settings(int, char **) override;
  void init() override;
  void setup() override;
  void compute(int, int) override;
  int modify_param(int, char **) override;
  double memory_usage() override;

  // init, setup and compute run these inside guarded(): an exception of the engine (bad
  // input it checks, or memory) becomes a LAMMPS error naming it instead of ending the process
  void init_style_and_engine();
  void setup_run();
  void compute_step(int, int);
  template <class F> void guarded(const char *what, F &&body);

  // last measured relative RMS force error of `check` (negative when never measured)
  double measured_error() const { return last_measured_error; }
  // exact sums computed for the error measurements (one per step and sample: a measurement of
  // the same step on the same atoms reuses the last one)
  long exact_sums() const { return exact_reference.sums; }
  const kifmm::Stats &engine_stats() const;
  int engine_order() const { return engine_options.order; }    // the order in use
  // tune yes: trees to be timed from the start of a run (its first evaluation chooses the tree,
  // tuning starts at the second) until the fastest is kept; with a tree that is not tuned (a
  // given leaf size or grid), until the second evaluation finds that
  bool tuning() const { return tune_pending || tuner.tuning(); }
  // the evaluations that settle the run's tree and order (tuning, and the measurement of the
  // error of a tuned tree other than the modelled one) are still to come: after them every
  // evaluation costs the same
  bool settling() const { return tuning() || verify_pending; }
  int engine_leaf_size() const { return engine_options.leaf_size; }
  int engine_grid() const { return engine_options.periodic_grid; }    // 0: the octree
  // time by phase since the setup of the current run (printed at its end)
  const KIFMMTiming &timing() const { return run_timing; }

 private:
  kifmm_lammps::KIFMMSettings kset;
  std::unique_ptr<kifmm::Evaluator> engine;
  kifmm::Options engine_options;
  double estimated_error = 0.0;
  double last_measured_error = -1.0;
  bool reported_first_evaluation = false;
  bool warned_coincident = false;
  // no leaf size given, one rank: the tree is chosen from the atom positions at the first
  // evaluation of each run (kifmm::choose_tree on the counts of the actual trees)
  bool tree_choice_pending = false;
  kifmm::TreeRequest tree_request;    // what the tree is chosen from (init)
  void choose_tree_from_atoms();
  // tune yes (the default): after the first evaluation of a run (and its accuracy check), the
  // trees near the chosen one are timed on the next evaluations and the fastest kept
  // (kifmm::TreeTuner; kspace_kifmm_tuning.cpp)
  bool tune_pending = false;
  kifmm::TreeTuner tuner;
  void select_tuned_tree();
  void tune_tree(double seconds, bool want_potential, double &comm_time, std::size_t &nsrc);
  void finish_tuning();
  KIFMMTiming run_timing;
  double memory_limit_mb = 0;    // 0 = unknown: no check

  // atoms of nonzero strength, reused between calls
  std::vector<int> index;              // local atom index of each point
  std::vector<double> xyz, strength;   // positions, q or m
  std::vector<double> pot, grad;
  // point dipoles (kspace_kifmm_dipoles.cpp): on when atoms have nonzero moments mu at init;
  // then the points are the atoms with a charge or a moment, moment holds mu (3 per point) and
  // hess the second derivatives of the potential (6 per point: xx yy zz xy xz yz)
  bool dipoles = false;
  std::vector<double> moment, hess;
  void dipole_init();
  bool is_point(int i) const;    // a source and target of the sum
  void evaluate_dipole_points(bool want_potential, double &comm_time, std::size_t &nsrc);
  // force and torque of point k (torque zero without dipoles), its energy
  void point_force(std::size_t k, double prefactor, double f[3], double t[3]) const;
  // the same from another evaluation's gradient g and (dipoles) Hessian h at point k
  void point_force(std::size_t k, double prefactor, const double *g, const double *h, double f[3], double t[3]) const;
  double point_energy(std::size_t k, double prefactor) const;
  void dipole_virial(double prefactor, bool global, bool peratom);
  // induced dipoles (fix kifmm/polarize, KIFMMPolarization; kspace_kifmm_polarize.cpp): solved
  // before each evaluation, written into moment and atom->mu
  class KIFMMPolarization *polarization = nullptr;
  void find_polarization();
  void polarize_points();
  // more than one rank: distributed evaluation over this communicator (world), open or
  // periodic boundaries; one rank uses the serial evaluate() (with its mutual near field)
  std::unique_ptr<kifmm::Communicator> kcomm;
  bool distributed() const;

  double strength_of(int i) const;
  bigint count_strong_atoms() const;
  double force_prefactor() const;    // F_i = prefactor * s_i * grad_i
  double energy_prefactor() const;   // E = prefactor * 0.5 * sum s_i phi_i
  void gather_points();
  // engine evaluation of the gathered points (then the pairs inside rigid bodies subtracted)
  void evaluate_points(bool want_potential, double &comm_time, std::size_t &nsrc);
  void per_atom_virial(double prefactor, double center[3]);
  void add_body_pair_virial(double prefactor, const double *offset, double *w) const;

  // measured error (kspace_kifmm_error.cpp): sampled against the exact sum, on free atoms'
  // forces and on rigid clumps' net forces and torques (negative: nothing of that kind)
  struct MeasuredError {
    double atoms = -1, clump_force = -1, clump_torque = -1, torques = -1;    // torques: of dipoles
    bigint natoms = 0, nclumps = 0;
    double worst() const;
    std::string describe() const;
  };
  MeasuredError measure_error(int nsamples);
  MeasuredError measure_dipole_error(int nsamples);
  MeasuredError clump_error(const std::vector<std::size_t> &pebbles, const std::vector<double> &a,
                            const std::vector<double> &e);
  // the current evaluation's difference from another of the same points (its gradients and,
  // with dipoles, Hessians) over all of them, measured as the error is
  MeasuredError difference_from(const std::vector<double> &g, const std::vector<double> &h);
  // the exact gradients at the last measurement's sample, reused by the next measurement of the
  // same step on the same atoms (the order search measures each order it tries on that sample)
  struct ExactReference {
    bigint step = -1;
    int order = -1;                  // kifmm::reference_order of the sum
    unsigned long long atoms = 0;    // hash of the positions and strengths
    std::vector<std::size_t> sample;
    std::vector<double> exact;
    long sums = 0;
  } exact_reference;
  void exact_gradient_at(const std::vector<std::size_t> &sample, std::vector<double> &exact);
  void check_error();
  // order from the accuracy: at the first evaluation of a run the error is measured on the
  // atoms and the order raised until the request is met, or lowered while it is still met
  static constexpr int verify_samples = kifmm::order_search_samples;
  static constexpr double verify_margin = kifmm::order_search_margin;    // sampled error wanted: 3/4 of the request
  bool verify_pending = false;
  double verified_error = -1.0;
  int chosen_order = 0;    // order the last measurement settled on (0: none), kept across runs
  static constexpr int min_tried_order = 3;    // lowest order the measurement tries
  void verify_accuracy(bool want_potential, double &comm_time, std::size_t &nsrc);

  // rigid bodies (fix clump/rigid, KIFMMRigidBodies): the pairs inside each body are left out
  // of the sum (kspace_kifmm_bodies.cpp). Per point: its body's ID (0: free atom), the lab
  // offset from the body's centre of mass, 1 / pebbles of its body, and the pair sums inside
  // its body in the lab frame (gradient 3, potential, pair virial 6)
  std::vector<class KIFMMRigidBodies *> bodies;
  std::vector<tagint> point_body;
  std::vector<double> point_arm, point_clump_weight, body_pairs;
  void find_rigid_bodies();
  void prepare_rigid_bodies();
  void subtract_body_pairs(bool potential);
  void check_pebble_dipoles();
  void charge_gradient(std::size_t k, const double *g, double gq[3]) const;
  void report_first_evaluation();
  void report_coincident_pairs(std::size_t local_pairs);
  void check_memory(std::size_t nsources);
  // periodic boundaries (kspace_kifmm_periodic.cpp)
  bool periodic = false;
  bool slab = false;    // boundary p p f (or p p s/m): periodic in x and y only
  bool warned_octree_fallback = false;    // a box no grid fits at this order (fit_periodic_box)
  int scalar_pressure_written = -1, scalar_pressure_user = -1;    // pressure/scalar (periodic_init)
  void periodic_init();
  void periodic_cell();
  void periodic_box(double center[3], double half_widths[3]) const;
  // a slab's z extent: the box's, or wider while atoms are outside the box in z (between
  // reneighborings, or during a run with shrink-wrapped z)
  bool slab_extent_set = false;
  double slab_extent[2] = {0.0, 0.0};
  void update_slab_extent();
  void periodic_root(kifmm::Options &o) const;
  bool periodic_fits(const kifmm::Options &o) const;
  void fit_periodic_box(kifmm::Options &o);
  std::string grid_cells_text(const kifmm::Options &o) const;
  void periodic_virial(double e_local, double prefactor);
  // the full virial tensor of p p p and slabs on the single-level grid: the engine's
  // own, or a grid evaluator next to the octree (virial_engine)
  bool periodic_tensor() const;
  std::unique_ptr<kifmm::Evaluator> virial_engine;
  kifmm::Evaluator &virial_evaluator();
  void periodic_tensor_virial(double prefactor, bool global, bool peratom);
  void store_point_virial(const std::vector<double> &w, bool global, bool peratom);

  // the fix scheduling the evaluations (fix kifmm/stride), found among the fixes at init
  class KIFMMForceSchedule *schedule = nullptr;
  void find_force_schedule();
};

}    // namespace LAMMPS_NS
