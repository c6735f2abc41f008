// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The stand-in of all ranks' points for the tree choice (kifmm::gather_layout): its octrees of
// leaf size kLayoutCell and more have the real points' cells and counts (open and periodic,
// clustered), its grids nearly the real occupancies, the choice made on it is the choice made
// on the points, the tuner walks the same trees on it, and a layout beyond kLayoutMaxPoints
// points is not built. Here on one process
// (the serial communicator, and one that stands for ranks holding copies of the same points);
// over MPI ranks: test_distributed.cpp (Distributed.PointLayout*).
#include "communicator.h"
#include "cost_model.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using kifmm::KernelSpec;
using namespace kifmm_test;

namespace {

// ranks that all hold copies of the same points: sums are multiplied by their number
class CopiesCommunicator : public kifmm::SerialCommunicator {
 public:
  explicit CopiesCommunicator(int copies) : copies_(copies) {}
  int size() const override { return copies_; }
  void allreduce_sum(double *data, std::size_t n) override
  {
    for (std::size_t i = 0; i < n; ++i) data[i] *= copies_;
  }
  void allreduce_sum(uint64_t *data, std::size_t n) override
  {
    for (std::size_t i = 0; i < n; ++i) data[i] *= (uint64_t) copies_;
  }

 private:
  int copies_;
};

void expect_same_counts(const kifmm::TreeCounts &a, const kifmm::TreeCounts &b, const std::string &what)
{
  SCOPED_TRACE(what);
  EXPECT_EQ(a.near_pairs, b.near_pairs);
  EXPECT_EQ(a.self_pairs, b.self_pairs);
  EXPECT_EQ(a.translations, b.translations);
  EXPECT_EQ(a.cells, b.cells);
  EXPECT_EQ(a.entries, b.entries);
  EXPECT_EQ(a.periodic_cells, b.periodic_cells);
}

struct LayoutCase {
  std::string name;
  Points points;
  kifmm::Options options;
};

std::vector<LayoutCase> layout_cases()
{
  kifmm::Options open;
  open.order = 6;
  const double c[3] = {0.0, 0.0, 0.0};
  // the clusters scaled into the periodic cell [-1, 1)^3 (and beyond its faces: wrapped)
  Points clusters = two_clusters(20000, 5);
  for (double &x : clusters.xyz) x *= 0.2;
  Points shifted = plummer(20000, 9);
  for (std::size_t i = 0; i < shifted.size(); ++i) shifted.xyz[3 * i] = 0.3 * shifted.xyz[3 * i] + 0.9;
  return {{"open plummer", plummer(20000, 3), open},
          {"open two clusters", two_clusters(20000, 4), open},
          {"periodic two clusters", clusters, periodic_options(5, 0, 1.0, c)},
          {"periodic plummer across a face", shifted, periodic_options(7, 0, 1.0, c)}};
}
}    // namespace

TEST(PointLayout, OctreesHaveTheRealCellsAndCounts)
{
  kifmm::SerialCommunicator serial;
  for (const LayoutCase &t : layout_cases()) {
    const std::size_t n = t.points.size();
    const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, t.options, n, t.points.xyz.data(), serial);
    ASSERT_EQ(layout.n, n);
    ASSERT_EQ(layout.xyz.size(), 3 * n);
    EXPECT_TRUE(layout.model.fixed_root);
    for (int leaf : {8, 13, 40, 128, 700}) {
      int d_real = -1, d_layout = -2;
      const kifmm::TreeCounts real = kifmm::actual_tree_counts(KernelSpec{}, t.options, n, t.points.xyz.data(), leaf, &d_real);
      const kifmm::TreeCounts stand_in = kifmm::actual_tree_counts(KernelSpec{}, layout.model, n, layout.xyz.data(), leaf, &d_layout);
      EXPECT_EQ(d_real, d_layout) << t.name << ", leaf " << leaf;
      expect_same_counts(real, stand_in, t.name + ", leaf " + std::to_string(leaf));
    }
  }
}

// a leaf below kLayoutCell splits cells the histogram did not: the stand-in is then uniform
// inside them, and its counts differ from the real ones (the test above is not trivially true)
TEST(PointLayout, LeavesBelowItsCellsDiffer)
{
  kifmm::SerialCommunicator serial;
  const LayoutCase t = layout_cases()[0];
  const std::size_t n = t.points.size();
  const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, t.options, n, t.points.xyz.data(), serial);
  const kifmm::TreeCounts real = kifmm::actual_tree_counts(KernelSpec{}, t.options, n, t.points.xyz.data(), 2);
  const kifmm::TreeCounts stand_in = kifmm::actual_tree_counts(KernelSpec{}, layout.model, n, layout.xyz.data(), 2);
  EXPECT_NE(real.near_pairs, stand_in.near_pairs);
}

TEST(PointLayout, GridsNearlyHaveTheRealOccupancies)
{
  kifmm::SerialCommunicator serial;
  for (const LayoutCase &t : layout_cases()) {
    if (!t.options.periodic) continue;
    const std::size_t n = t.points.size();
    const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, t.options, n, t.points.xyz.data(), serial);
    const auto real = kifmm::model_grids(KernelSpec{}, t.options, n, t.points.xyz.data(), true);
    const auto stand_in = kifmm::model_grids(KernelSpec{}, layout.model, n, layout.xyz.data(), true);
    ASSERT_EQ(real.size(), stand_in.size());
    ASSERT_GE(real.size(), 3u);
    for (std::size_t k = 0; k < real.size(); ++k) {
      EXPECT_EQ(real[k].grid, stand_in[k].grid);
      EXPECT_NEAR(stand_in[k].cost / real[k].cost, 1.0, 0.05) << t.name << ", grid " << real[k].grid;
    }
  }
}

TEST(PointLayout, ChoiceOnItIsTheChoiceOnThePoints)
{
  kifmm::SerialCommunicator serial;
  for (const LayoutCase &t : layout_cases()) {
    const std::size_t n = t.points.size();
    const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, t.options, n, t.points.xyz.data(), serial);
    const kifmm::TreeRequest request{n, 0, t.options.periodic ? -1 : 0, true};
    kifmm::Options on_points = t.options, on_layout = t.options;
    const kifmm::TreeChoice a = kifmm::choose_tree_from_points(KernelSpec{}, request, on_points, n, t.points.xyz.data());
    const kifmm::TreeChoice b = kifmm::choose_tree_from_layout(KernelSpec{}, request, on_layout, layout);
    EXPECT_EQ(a.leaf_size, b.leaf_size) << t.name;
    EXPECT_EQ(a.grid, b.grid) << t.name;
    EXPECT_NEAR(b.cost / a.cost, 1.0, 0.05) << t.name;
    EXPECT_EQ(on_points.leaf_size, on_layout.leaf_size);
    EXPECT_EQ(on_points.periodic_grid, on_layout.periodic_grid);
    EXPECT_FALSE(on_layout.fixed_root && !t.options.fixed_root);    // the evaluator's options keep their root
  }
}

// several ranks: their points' counts add up (here copies of the same points); beyond
// kLayoutMaxPoints no layout (the uniform choice stays)
TEST(PointLayout, CountsAddUpOverRanksUpToItsSize)
{
  const Points p = plummer(5000, 11);
  kifmm::Options o;
  o.order = 5;
  CopiesCommunicator two(2);
  const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, o, p.size(), p.xyz.data(), two);
  EXPECT_EQ(layout.n, 2 * p.size());
  EXPECT_DOUBLE_EQ(layout.model.model_share, 0.5);    // each rank holds half the points
  ASSERT_EQ(layout.xyz.size(), 3 * layout.n);
  // every cell of the copies' tree holds twice the points of the single set's tree
  int d_one = -1, d_two = -2;
  const kifmm::TreeCounts one = kifmm::actual_tree_counts(KernelSpec{}, o, p.size(), p.xyz.data(), 50, &d_one);
  const kifmm::TreeCounts both = kifmm::actual_tree_counts(KernelSpec{}, layout.model, layout.n, layout.xyz.data(), 100, &d_two);
  EXPECT_EQ(d_one, d_two);
  EXPECT_EQ(4 * one.self_pairs, both.self_pairs);
  EXPECT_EQ(one.translations, both.translations);
  const std::size_t many = kifmm::kLayoutMaxPoints / p.size() + 1;
  CopiesCommunicator too_many((int) many);
  const kifmm::PointLayout none = kifmm::gather_layout(KernelSpec{}, o, p.size(), p.xyz.data(), too_many);
  EXPECT_EQ(none.n, many * p.size());
  EXPECT_TRUE(none.xyz.empty());
}

// The tuner of several ranks models its ladders on the stand-in (the layout's options: root
// fixed) and builds its evaluators from the evaluator's options (open: the root follows the
// points): on the same times it walks the same trees as on the points themselves (open sets,
// whose ladders are octrees only; the grids' modelled costs differ slightly). A layout without
// points (beyond kLayoutMaxPoints) gives the uniform model's ladders.
TEST(PointLayout, TunerWalksTheTreesOfThePoints)
{
  kifmm::SerialCommunicator serial;
  const auto time = [](const kifmm::Options &o) {
    return o.periodic_grid > 0 ? 1.0 + 0.02 * o.periodic_grid : 1.0 + std::fabs(std::log(o.leaf_size / 300.0));
  };
  for (const LayoutCase &t : layout_cases()) {
    const std::size_t n = t.points.size();
    const kifmm::PointLayout layout = kifmm::gather_layout(KernelSpec{}, t.options, n, t.points.xyz.data(), serial);
    const kifmm::TreeRequest request{n, 0, t.options.periodic ? -1 : 0, true};
    kifmm::Options start = t.options;
    kifmm::choose_tree_from_points(KernelSpec{}, request, start, n, t.points.xyz.data());
    kifmm::TreeTuner on_points(KernelSpec{}, request, start, n, t.points.xyz.data());
    kifmm::TreeTuner on_layout(KernelSpec{}, request, start, layout);
    // a layout without points (beyond its size): the uniform model's ladders
    kifmm::PointLayout beyond = layout;
    beyond.xyz.clear();
    const kifmm::Options uniform_start = kifmm::plan_tree(t.options, request).options;
    kifmm::TreeTuner on_beyond(KernelSpec{}, request, uniform_start, beyond);
    kifmm::TreeTuner uniform(KernelSpec{}, request, uniform_start, n, nullptr);
    for (kifmm::TreeTuner *tuner : {&on_points, &on_layout, &on_beyond, &uniform}) {
      const kifmm::Options &from = tuner == &on_beyond || tuner == &uniform ? uniform_start : start;
      std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(KernelSpec{}, from);
      for (int k = 0; tuner->tuning() && k < 1000; ++k) {
        tuner->select(ev);
        EXPECT_EQ(ev->options().fixed_root, from.fixed_root) << t.name;
        EXPECT_EQ(ev->options().root_half_width, from.root_half_width) << t.name;
        tuner->record(time(ev->options()));
      }
      EXPECT_FALSE(tuner->tuning());
      tuner->finish(ev);
    }
    ASSERT_GE(on_layout.timed().size(), 2u) << t.name;
    ASSERT_GE(uniform.timed().size(), 2u) << t.name;
    ASSERT_EQ(on_beyond.timed().size(), uniform.timed().size()) << t.name;
    for (std::size_t i = 0; i < uniform.timed().size(); ++i) {
      EXPECT_EQ(on_beyond.timed()[i].tree.leaf_size, uniform.timed()[i].tree.leaf_size) << t.name << ", tree " << i;
      EXPECT_EQ(on_beyond.timed()[i].tree.grid, uniform.timed()[i].tree.grid) << t.name << ", tree " << i;
      EXPECT_EQ(on_beyond.timed()[i].tree.cost, uniform.timed()[i].tree.cost) << t.name << ", tree " << i;
    }
    if (t.options.periodic) continue;
    ASSERT_EQ(on_points.timed().size(), on_layout.timed().size()) << t.name;
    for (std::size_t i = 0; i < on_points.timed().size(); ++i) {
      EXPECT_EQ(on_points.timed()[i].tree.leaf_size, on_layout.timed()[i].tree.leaf_size) << t.name << ", tree " << i;
      EXPECT_EQ(on_points.timed()[i].tree.depth, on_layout.timed()[i].tree.depth) << t.name << ", tree " << i;
      EXPECT_EQ(on_points.timed()[i].tree.cost, on_layout.timed()[i].tree.cost) << t.name << ", tree " << i;
    }
  }
}
