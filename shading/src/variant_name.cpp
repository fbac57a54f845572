// Variant and derivative-source names, parsed in this one place for the
// renderer, the specs, the runner and the CLI.
#include <charconv>
#include <string>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {

std::optional<DerivativeSource> ParseDerivativeSource(std::string_view name) {
  if (name == "quad" || name == "quad-fine") return DerivativeSource::kQuadFine;
  if (name == "quad-coarse") return DerivativeSource::kQuadCoarse;
  if (name == "analytic") return DerivativeSource::kAnalytic;
  return std::nullopt;
}

std::string_view DerivativeSourceName(DerivativeSource source) {
  switch (source) {
    case DerivativeSource::kQuadFine: return "quad";
    case DerivativeSource::kQuadCoarse: return "quad-coarse";
    case DerivativeSource::kAnalytic: return "analytic";
  }
  return "quad";
}

Result<VariantName> ParseVariantName(std::string_view name) {
  constexpr std::string_view kSupersample = "supersample-";
  VariantName v;
  if (name.substr(0, kSupersample.size()) == kSupersample) {
    const std::string_view digits = name.substr(kSupersample.size());
    int n = 0;
    auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), n);
    if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() || n < 1 || n > kMaxSupersampleN)
      return Result<VariantName>::Failure("variant '" + std::string(name) + "': supersample-N needs N in 1.." +
                                          std::to_string(kMaxSupersampleN));
    v.kind = VariantName::Kind::kSupersample;
    v.info = FindVariant("none");
    v.spp_n = n;
    return v;
  }
  v.info = FindVariant(name);
  if (!v.info)
    return Result<VariantName>::Failure("unknown variant '" + std::string(name) +
                                        "' (see `shimmer variants`, or supersample-N)");
  return v;
}

}  // namespace shimmer::shading
