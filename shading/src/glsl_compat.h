// Compiles the GLSL shading core as C++. Include inside a namespace after
// defining `real`; the GLSL vector and matrix names then alias GLM types of
// that precision and GLSL's built-in functions resolve to GLM's.
//
//   namespace glsl_f64 {
//   using real = double;
//   #include "glsl_compat.h"
//   #include "core.glsl"
//   }
//
// Deliberately not include-guarded: each namespace gets its own aliases.
// <glm/glm.hpp> must be included at global scope first.

using vec2 = glm::vec<2, real, glm::defaultp>;
using vec3 = glm::vec<3, real, glm::defaultp>;
using vec4 = glm::vec<4, real, glm::defaultp>;
using mat2 = glm::mat<2, 2, real, glm::defaultp>;
using ivec2 = glm::ivec2;
using uint = unsigned int;

using glm::abs;
using glm::acos;
using glm::asinh;
using glm::atan;
using glm::ceil;
using glm::clamp;
using glm::cos;
using glm::cross;
using glm::dot;
using glm::exp;
using glm::exp2;
using glm::floor;
using glm::inversesqrt;
using glm::length;
using glm::log;
using glm::log2;
using glm::max;
using glm::min;
using glm::mix;
using glm::normalize;
using glm::pow;
using glm::sin;
using glm::sinh;
using glm::sqrt;
using glm::tan;
