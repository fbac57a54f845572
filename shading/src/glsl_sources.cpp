#include "shimmer/shading/shading.h"

namespace shimmer::shading {
namespace embedded {
std::span<const std::pair<std::string_view, std::string_view>> Sources();
}

std::span<const std::pair<std::string_view, std::string_view>> GlslSources() { return embedded::Sources(); }
}  // namespace shimmer::shading
