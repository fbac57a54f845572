#include <gtest/gtest.h>

#include "shading.h"

namespace shimmer::shading {
TEST(Catalogue, IdsMatchGlslConstants) { EXPECT_TRUE(CatalogueMatchesGlsl()); }
}  // namespace shimmer::shading
