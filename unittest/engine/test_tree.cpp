#include "test_util.h"
#include <gtest/gtest.h>
