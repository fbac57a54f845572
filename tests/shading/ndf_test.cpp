#include <gtest/gtest.h>

#include "shimmer/renderer/shading.h"

namespace shimmer::shading {
TEST(Catalogue, IdsMatchGlslConstants) { EXPECT_TRUE(CatalogueMatchesGlsl()); }
}  // namespace shimmer::shading
