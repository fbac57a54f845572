// A user's filter variant: a GLSL file defining userVariant(...), with its
// parameters declared in comment lines of the file itself:
//
//   // shimmer-variant: one line that says what the variant does
//   // shimmer-param: k = 0.5 in [0, 4]: what k means
//   // shimmer-params: none            (a variant that reads no parameter)
//
// A file without shimmer-param lines reads the eight built-in parameters
// (fp_max, fp_min_cap, sigma2, kappa) with their defaults and ranges. The
// GLSL reads a parameter as `p.k` from `UserParams p`; the renderer carries
// at most eight, in the slots of VariantParams (docs/variants.md).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/shading/shading.h"

namespace shimmer::shading {

inline constexpr int kMaxUserParams = 8;  // the slots of VariantParams

struct UserParam {
  std::string name;
  double default_value = 0, lo = 0, hi = 0;  // accepted: [lo, hi]
  std::string meaning;
  const ParamField* slot = nullptr;  // where the renderer carries it
  int line = 0;                      // its shimmer-param line in the file
};

// Resolved values of a user variant's parameters.
struct UserParams {
  Params<double> values;                              // in the slots the kernel reads
  std::vector<std::pair<std::string, double>> shown;  // every declared parameter with its value
};

struct UserVariant {
  std::string file;  // as the user gave it: messages name it so
  std::string text;
  std::string summary;              // the shimmer-variant line, or ""
  std::vector<UserParam> params;    // in declaration order
  bool declared = false;            // false: the eight built-in parameters are implied
  std::string content_hash;         // Fnv1a64Hex of the text: what job ids hash
};

// The declarations of `text`; errors read "<file>:<line>: <problem>".
Result<UserVariant> ParseUserVariant(std::string text, const std::string& file);
// The file read whole and parsed; a missing or unreadable file is named.
Result<UserVariant> LoadUserVariant(const std::string& path);

const UserParam* FindUserParam(const UserVariant& v, std::string_view name);

// The declared defaults overridden by `overrides`; every value is checked
// finite and in its declared range, an unknown name is listed against the
// declared ones. `shown` holds every declared parameter with its value.
Result<UserParams> ResolveUserParams(const UserVariant& v,
                                     std::span<const std::pair<std::string, double>> overrides);

// The GLSL the kernel compiles before the user's file: struct UserParams with
// one real per declared parameter, userParams(VariantParams) that fills it
// from the slots, and variantParams(UserParams) for calls of built-in
// variants (the declared values in their slots, built-in defaults elsewhere).
std::string UserParamsGlsl(const UserVariant& v);

// What `shimmer variants --file` prints: the summary and each parameter with
// default, range and meaning.
std::string DescribeUserVariant(const UserVariant& v);

}  // namespace shimmer::shading
