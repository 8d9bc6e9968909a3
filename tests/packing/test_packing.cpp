#include <gtest/gtest.h>
#include "netdem/packing/ballistic.hpp"
TEST(Packing, Placeholder) { EXPECT_GT(netdem::packing::ballistic_deposition({}).size(), 0u); }
