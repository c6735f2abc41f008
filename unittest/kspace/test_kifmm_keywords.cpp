// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The keyword parser of kspace_style kifmm / kspace_modify kifmm (no LAMMPS needed).
#include "kifmm_keywords.h"

#include <gtest/gtest.h>

using namespace kifmm_lammps;

namespace {

std::string parse(std::vector<std::string> args, KIFMMSettings &s, int &consumed)
{
  return parse_kifmm_keywords(args, s, consumed);
}

TEST(KifmmKeywords, AccuracyRange)
{
  KIFMMSettings s;
  EXPECT_EQ(parse_accuracy("1e-4", s), "");
  EXPECT_DOUBLE_EQ(s.accuracy, 1e-4);
  for (const char *bad : {"0", "1", "-1e-3", "2", "abc", "", "1e-3x", "nan", "inf"})
    EXPECT_NE(parse_accuracy(bad, s), "") << bad;
  EXPECT_NE(parse_accuracy("0", s).find("out of range"), std::string::npos);
  EXPECT_NE(parse_accuracy("abc", s).find("'abc'"), std::string::npos);
}

TEST(KifmmKeywords, Kernels)
{
  KIFMMSettings s;
  int n = 0;
  EXPECT_EQ(parse({"kifmm", "kernel", "gravity", "6.674e-11"}, s, n), "");
  EXPECT_EQ(n, 4);
  EXPECT_EQ(s.kernel, LongRangeKernel::Gravity);
  EXPECT_DOUBLE_EQ(s.gravity_G, 6.674e-11);
  EXPECT_EQ(parse({"kifmm", "kernel", "yukawa", "2.5", "order", "7"}, s, n), "");
  EXPECT_EQ(s.kernel, LongRangeKernel::Yukawa);
  EXPECT_DOUBLE_EQ(s.kappa, 2.5);
  EXPECT_EQ(s.order, 7);
  EXPECT_EQ(n, 6);
  EXPECT_EQ(parse({"kifmm", "kernel", "coulomb"}, s, n), "");
  EXPECT_EQ(s.kernel, LongRangeKernel::Coulomb);
}

TEST(KifmmKeywords, ErrorsNameTheBadToken)
{
  KIFMMSettings s;
  int n = 0;
  EXPECT_NE(parse({"kifmm", "kernel", "lennard"}, s, n).find("'lennard'"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "kernel", "gravity"}, s, n).find("needs a value"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "kernel", "gravity", "-1"}, s, n).find("G must be > 0"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "kernel", "yukawa", "x"}, s, n).find("'x'"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "order", "1"}, s, n).find("out of range"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "order", "99"}, s, n).find("out of range"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "order", "6.5"}, s, n).find("not an integer"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "leaf", "0"}, s, n).find("out of range"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "check", "10"}, s, n).find("2 values"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "check", "10", "0"}, s, n).find("NSAMPLE"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "bogus"}, s, n).find("unknown keyword 'bogus'"), std::string::npos);
  EXPECT_NE(parse({"kifmm"}, s, n).find("no keyword"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "order"}, s, n).find("needs a value"), std::string::npos);
}

TEST(KifmmKeywords, YesNoKeywords)
{
  KIFMMSettings s;
  int n = 0;
  EXPECT_TRUE(s.tune);
  EXPECT_FALSE(s.jeans);
  EXPECT_EQ(parse({"kifmm", "tune", "no", "jeans", "yes"}, s, n), "");
  EXPECT_EQ(n, 5);
  EXPECT_FALSE(s.tune);
  EXPECT_TRUE(s.jeans);
  EXPECT_EQ(parse({"kifmm", "tune", "yes"}, s, n), "");
  EXPECT_TRUE(s.tune);
  EXPECT_NE(parse({"kifmm", "tune"}, s, n).find("'tune' needs a value: yes or no"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "tune", "maybe"}, s, n).find("tune 'maybe' must be yes or no"), std::string::npos);
  EXPECT_NE(parse({"kifmm", "jeans", "1"}, s, n).find("jeans '1' must be yes or no"), std::string::npos);
}

TEST(KifmmKeywords, StopsAtGenericKspaceModifyKeywords)
{
  KIFMMSettings s;
  int n = 0;
  EXPECT_EQ(parse({"kifmm", "leaf", "300", "compute", "no"}, s, n), "");
  EXPECT_EQ(n, 3);
  EXPECT_EQ(s.leaf, 300);
  EXPECT_EQ(parse({"kifmm", "check", "100", "500", "cache", "none"}, s, n), "");
  EXPECT_EQ(n, 6);
  EXPECT_EQ(s.check_every, 100);
  EXPECT_EQ(s.check_samples, 500);
  EXPECT_EQ(s.cache_dir, "none");
}

}    // namespace
