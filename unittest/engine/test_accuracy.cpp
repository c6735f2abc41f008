#include "test_util.h"

#include <gtest/gtest.h>

using namespace kifmm_test;
using kifmm::KernelSpec;

TEST(EngineAccuracy, UniformCubeQuick)
{
  Points p = uniform_cube(4000, 1);
  for (int order : {4, 6, 8}) {
    Errors e = fmm_errors(KernelSpec{}, order, 64, p);
    printf("order %d pot %.3e grad %.3e\n", order, e.pot, e.grad);
  }
}
