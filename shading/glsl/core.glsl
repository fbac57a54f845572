// The shading core in dependency order. Kernels include this file; C++
// includes it through shading_glsl.cpp.
#include "common.glsl"
#include "variant_table.glsl"  // generated from shading/variant_table.json
#include "ndf.glsl"
#include "ggx_rect.glsl"
#include "variants.glsl"
#include "brdf.glsl"
#include "sg.glsl"
#include "sg_light.glsl"
#include "normal_map.glsl"
#include "scene.glsl"
#include "glints.glsl"
#include "pixel.glsl"
