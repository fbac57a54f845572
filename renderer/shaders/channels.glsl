// Channel planes of the renderer's image buffer: the first plane of each
// layer. Included by render.comp and, as C++, by renderer/render/gpu_layout.h,
// which builds the Channel enum from these, so the two never disagree.
const int CH_BEAUTY = 0, CH_SPECULAR = 3, CH_DIFFUSE = 6, CH_MOTION = 9, CH_DEPTH = 11, CH_NORMAL = 12,
          CH_ROUGHNESS = 15, CH_FOOTPRINT = 16, CH_STDERR = 18, CH_COUNT = 19, CH_M2 = 20, CH_PLANES = 21;
