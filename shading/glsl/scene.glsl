// Scene geometry of the renderer: the pinhole camera with ray differentials,
// analytic primitives (sphere, capsule, plane with a procedural normal
// pattern), their normals and normal derivatives, and a BVH walk.
//
// The scene is a flat array of vec4 words (renderer/scene/scene.cpp packs it;
// floats hold small integers exactly):
//   word 0                       (bvhPrimCount, nodeCount, firstPrimWord, unboundedPrimCount)
//   node i, words 1 + 2i, 2 + 2i (bbmin, skip), (bbmax, leaf's primitive + 1; 0 = interior)
//     nodes in depth-first order: an interior node's first child is the next
//     node, `skip` is the node after its subtree (a stackless walk: no local
//     arrays, which SIMD CPU drivers such as lavapipe handle slowly)
//   prim j, words firstPrimWord + 3j ..
//                                (type, radius or height, bumpSlope, bumpFrequency), (a, map), (b, 0)
//                                map: the word of the primitive's normal-map header (normal_map.glsl), 0: none
// Unbounded primitives (planes) follow the BVH's primitives and are always tested.
// Normal-map headers and texels follow the primitives, then the meshes:
//   a mesh primitive             (PRIM_MESH, 0, 0, 0), (bbmin, map), (bbmax, its header word)
//   mesh header                  (nodeCount, firstNodeWord, firstTriangleWord, triangleCount)
//   node i, 2 words              (bbmin, offset), (bbmax, count): the flattened binned-SAH
//                                BVH of triangle_bvh.h (count 0: interior, its left child
//                                next, `offset` the right; else triangles offset.. of the leaf)
//   triangle j, 3 words          (corner k's position, corner k's vertex word), k = 0, 1, 2
//   vertex, 3 words              (normal, u), (tangent, handedness w), (v, map, 0, 0)
// A ray that hits a triangle reports the triangle's first word as its primitive:
// those words lie past every primitive's, so the number says which it is, and
// loadPrim gives a PRIM_TRIANGLE for it. Mesh code is compiled only where the
// includer defines SHIMMER_MESHES (the kernel of a scene with meshes, the C++
// oracle): every other kernel's SPIR-V stays what it was, and with it the ids
// of the results stored from it.
// The includer provides `vec4 sceneWord(int i)` (normal_map.glsl, included
// first, declares the empty scene of stand-alone compile checks).

const int PRIM_SPHERE = 0;
const int PRIM_CAPSULE = 1;
const int PRIM_PLANE = 2;
const int PRIM_MESH = 3;      // a triangle mesh with its own BVH
const int PRIM_TRIANGLE = 4;  // one of its triangles, as a hit names it

// What kinds of primitive a scene holds, a bit mask. The GPU kernel makes it a
// specialization constant: SIMD CPU drivers (lavapipe) run both sides of every
// branch under a lane mask, so code for a kind the scene lacks still costs its
// full time unless the compiler can drop it (a capsule test halved the sphere
// scene's sample rate). The C++ oracle handles every kind.
const int SCENE_SPHERES = 1;
const int SCENE_CAPSULES = 2;
const int SCENE_PLANES = 4;
const int SCENE_BUMPS = 8;  // planes with a normal pattern
const int SCENE_NORMAL_MAPS = 16;  // primitives with a normal map
const int SCENE_MESHES = 32;  // triangle meshes (with SHIMMER_MESHES)
const int SCENE_SHADOWS = 64;  // the light casts shadows: every shaded point traces a ray to it
const int SCENE_ROUGHNESS_MAPS = 128;  // meshes whose roughness texture scales alpha per texel
#ifndef SHIMMER_SCENE_FEATURES
const int SCENE_FEATURES = SCENE_SPHERES | SCENE_CAPSULES | SCENE_PLANES | SCENE_BUMPS | SCENE_NORMAL_MAPS |
                           SCENE_MESHES | SCENE_ROUGHNESS_MAPS;
#endif
const real RAY_TMIN = real(1e-4);
const real RAY_TMAX = real(1e30);

// ---- camera -----------------------------------------------------------------

// Orthonormal pinhole camera; pixel (0, 0) is the top-left corner of the image.
struct Camera {
  vec3 pos;
  vec3 fwd;
  vec3 right;
  vec3 up;
  real tanHalfFovY;
  real aspect;
  vec2 size;  // pixels
};

// A camera ray with the screen derivatives of its unit direction (Igehy 1999,
// "Tracing Ray Differentials"); the origin is the same for every pixel.
struct Ray {
  vec3 o;
  vec3 d;
  vec3 ddx;
  vec3 ddy;
};

// d normalize(v) for a change dv of v.
vec3 dNormalize(vec3 v, vec3 dv) {
  real inv = inversesqrt(max(dot(v, v), real(1e-30)));
  vec3 n = v * inv;
  return (dv - n * dot(n, dv)) * inv;
}

Ray cameraRay(Camera c, vec2 pix) {
  real sx = c.tanHalfFovY * c.aspect;
  real sy = c.tanHalfFovY;
  real nx = real(2) * pix.x / c.size.x - real(1);
  real ny = real(1) - real(2) * pix.y / c.size.y;
  vec3 D = c.fwd + c.right * (nx * sx) + c.up * (ny * sy);
  Ray r;
  r.o = c.pos;
  r.d = normalize(D);
  r.ddx = dNormalize(D, c.right * (real(2) * sx / c.size.x));
  r.ddy = dNormalize(D, c.up * (real(-2) * sy / c.size.y));
  return r;
}

// Pixel position of world point p seen by camera c (for motion vectors).
vec2 projectToPixel(Camera c, vec3 p) {
  vec3 q = p - c.pos;
  real z = max(dot(q, c.fwd), real(1e-9));
  real nx = dot(q, c.right) / (z * c.tanHalfFovY * c.aspect);
  real ny = dot(q, c.up) / (z * c.tanHalfFovY);
  return vec2((nx + real(1)) * real(0.5) * c.size.x, (real(1) - ny) * real(0.5) * c.size.y);
}

// ---- primitives -------------------------------------------------------------

struct Prim {
  int type;
  real radius;     // sphere, capsule; the plane's height y
  real bumpSlope;  // plane: maximum slope of each normal-pattern wave (0 = flat)
  real bumpFreq;   // plane: angular frequency of the base wave (radians per unit)
  vec3 a;          // sphere centre; capsule end
  vec3 b;          // capsule end
  int map;         // normal-map header word, 0: none
};

bool isSphere(Prim p) { return (SCENE_FEATURES & SCENE_SPHERES) != 0 && p.type == PRIM_SPHERE; }
bool isCapsule(Prim p) { return (SCENE_FEATURES & SCENE_CAPSULES) != 0 && p.type == PRIM_CAPSULE; }
bool isPlane(Prim p) { return (SCENE_FEATURES & SCENE_PLANES) != 0 && p.type == PRIM_PLANE; }
bool isBumpy(Prim p) { return (SCENE_FEATURES & SCENE_BUMPS) != 0 && p.type == PRIM_PLANE && p.bumpSlope != real(0); }
bool isMapped(Prim p) { return (SCENE_FEATURES & SCENE_NORMAL_MAPS) != 0 && p.map > 0; }

int scenePrimWord(int index) { return int(sceneWord(0).z) + 3 * index; }

#ifdef SHIMMER_MESHES
bool isMesh(Prim p) { return (SCENE_FEATURES & SCENE_MESHES) != 0 && p.type == PRIM_MESH; }
bool isTriangle(Prim p) { return (SCENE_FEATURES & SCENE_MESHES) != 0 && p.type == PRIM_TRIANGLE; }

// A hit's primitive number is a triangle's word when it lies past the
// primitives' words.
bool isTriangleId(int index) {
  vec4 header = sceneWord(0);
  return (SCENE_FEATURES & SCENE_MESHES) != 0 && index >= scenePrimWord(int(header.x) + int(header.w));
}

// The triangle at `word`: `radius` keeps the word (a float holds it exactly
// below 2^24), `a` and `b` its first corners, `map` its mesh's normal map.
Prim loadTriangle(int word) {
  Prim p;
  p.type = PRIM_TRIANGLE;
  p.radius = real(word);
  p.bumpSlope = real(0);
  p.bumpFreq = real(0);
  vec4 w0 = sceneWord(word);
  vec4 w1 = sceneWord(word + 1);
  p.a = vec3(w0.x, w0.y, w0.z);
  p.b = vec3(w1.x, w1.y, w1.z);
  p.map = int(sceneWord(int(w0.w) + 2).y);
  return p;
}
#endif

Prim loadPrim(int index) {
#ifdef SHIMMER_MESHES
  if (isTriangleId(index)) return loadTriangle(index);
#endif
  int w = scenePrimWord(index);
  vec4 w0 = sceneWord(w);
  vec4 w1 = sceneWord(w + 1);
  vec4 w2 = sceneWord(w + 2);
  Prim p;
  p.type = int(w0.x);
  p.radius = w0.y;
  p.bumpSlope = w0.z;
  p.bumpFreq = w0.w;
  p.a = vec3(w1.x, w1.y, w1.z);
  p.b = vec3(w2.x, w2.y, w2.z);
  p.map = int(w1.w);
  return p;
}

// Nearest t > RAY_TMIN of a unit-direction ray with a sphere, or -1. The
// discriminant uses the squared distance from the centre to the ray's line,
// which stays accurate for tiny, distant spheres (pbrt-v4's approach).
real intersectSphere(vec3 o, vec3 d, vec3 c, real r) {
  vec3 oc = o - c;
  real b = dot(oc, d);
  vec3 perp = oc - d * b;
  real disc = r * r - dot(perp, perp);
  if (disc < real(0)) return real(-1);
  real h = sqrt(disc);
  real t = -b - h;
  if (t > RAY_TMIN) return t;
  t = -b + h;
  if (t > RAY_TMIN) return t;
  return real(-1);
}

// Capsule (segment a-b, radius r): the infinite cylinder solved like the
// sphere above, from the ray's closest approach to the axis (thin, distant
// wires stay accurate in float), then the end caps as spheres.
real intersectCapsule(vec3 o, vec3 d, vec3 a, vec3 b, real r) {
  vec3 ba = b - a;
  real len = length(ba);
  vec3 u = ba / len;
  vec3 oa = o - a;
  vec3 dp = d - u * dot(d, u);
  vec3 op = oa - u * dot(oa, u);
  real qa = dot(dp, dp);
  real best = real(-1);
  if (qa > real(1e-12)) {
    real t0 = -dot(op, dp) / qa;
    vec3 w = op + dp * t0;
    real disc = r * r - dot(w, w);
    if (disc < real(0)) return real(-1);
    real h = sqrt(disc / qa);
    real t = t0 - h;
    if (!(t > RAY_TMIN)) t = t0 + h;
    real y = dot(oa + d * t, u);
    if (t > RAY_TMIN && y > real(0) && y < len) best = t;
  }
  real t1 = intersectSphere(o, d, a, r);
  real t2 = intersectSphere(o, d, b, r);
  if (t1 > real(0) && (best < real(0) || t1 < best)) best = t1;
  if (t2 > real(0) && (best < real(0) || t2 < best)) best = t2;
  return best;
}

real intersectPlane(vec3 o, vec3 d, real height) {
  if (abs(d.y) < real(1e-12)) return real(-1);
  real t = (height - o.y) / d.y;
  return t > RAY_TMIN ? t : real(-1);
}

real intersectPrim(Prim p, vec3 o, vec3 d) {
  if (isSphere(p)) return intersectSphere(o, d, p.a, p.radius);
  if (isCapsule(p)) return intersectCapsule(o, d, p.a, p.b, p.radius);
  if (isPlane(p)) return intersectPlane(o, d, p.radius);
  return real(-1);
}

// Slab test; returns the entry distance or RAY_TMAX for a miss.
real intersectBox(vec3 o, vec3 invD, vec3 lo, vec3 hi, real tmax) {
  vec3 t0 = (lo - o) * invD;
  vec3 t1 = (hi - o) * invD;
  vec3 tn = min(t0, t1);
  vec3 tf = max(t0, t1);
  real enter = max(max(tn.x, tn.y), max(tn.z, real(0)));
  real leave = min(min(tf.x, tf.y), min(tf.z, tmax));
  return enter <= leave ? enter : RAY_TMAX;
}

struct Hit {
  int prim;  // -1: miss
  real t;
};

real safeInverse(real x) { return real(1) / (abs(x) > real(1e-20) ? x : real(1e-20)); }

#ifdef SHIMMER_MESHES
// ---- triangle meshes ----------------------------------------------------------

// The watertight ray/triangle test of Woop, Benthin and Wald 2013 ("Watertight
// Ray/Triangle Intersection", JCGT 2(1)), as triangle_bvh.cpp runs it: the
// ray's space sheared so that the ray runs along +z, where the three edge
// functions decide the hit, so that a ray through a shared edge or vertex hits
// at least one of the triangles. (The CPU's double fallback for an edge
// function of exactly 0 is left out: a kernel has no double; the C++ oracle is
// double throughout.)
struct ShearedRay {
  int kx;
  int ky;
  int kz;
  vec3 s;  // Sx, Sy, Sz
};

ShearedRay shearedRay(vec3 d) {
  vec3 a = abs(d);
  ShearedRay r;
  r.kz = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
  r.kx = r.kz == 2 ? 0 : r.kz + 1;
  r.ky = r.kx == 2 ? 0 : r.kx + 1;
  if (d[r.kz] < real(0)) {  // keeps the triangles' winding
    int k = r.kx;
    r.kx = r.ky;
    r.ky = k;
  }
  r.s = vec3(d[r.kx] / d[r.kz], d[r.ky] / d[r.kz], real(1) / d[r.kz]);
  return r;
}

// The triangle's t, or -1.
real intersectTriangle(ShearedRay r, vec3 o, vec3 v0, vec3 v1, vec3 v2) {
  vec3 a = v0 - o;
  vec3 b = v1 - o;
  vec3 c = v2 - o;
  real ax = a[r.kx] - r.s.x * a[r.kz];
  real ay = a[r.ky] - r.s.y * a[r.kz];
  real bx = b[r.kx] - r.s.x * b[r.kz];
  real by = b[r.ky] - r.s.y * b[r.kz];
  real cx = c[r.kx] - r.s.x * c[r.kz];
  real cy = c[r.ky] - r.s.y * c[r.kz];
  real u = cx * by - cy * bx;
  real v = ax * cy - ay * cx;
  real w = bx * ay - by * ax;
  if ((u < real(0) || v < real(0) || w < real(0)) && (u > real(0) || v > real(0) || w > real(0))) return real(-1);
  real det = u + v + w;
  if (det == real(0)) return real(-1);
  real t = (u * (r.s.z * a[r.kz]) + v * (r.s.z * b[r.kz]) + w * (r.s.z * c[r.kz])) / det;
  return t > RAY_TMIN ? t : real(-1);
}

// A triangle's corners and vertex words: its three scene words from `word`
// on, each a corner's position and its vertex's word.
struct TriangleCorners {
  vec3 p0;
  vec3 p1;
  vec3 p2;
  int v0;  // vertex words
  int v1;
  int v2;
};

TriangleCorners triangleAt(int word) {
  vec4 w0 = sceneWord(word);
  vec4 w1 = sceneWord(word + 1);
  vec4 w2 = sceneWord(word + 2);
  TriangleCorners c;
  c.p0 = vec3(w0.x, w0.y, w0.z);
  c.p1 = vec3(w1.x, w1.y, w1.z);
  c.p2 = vec3(w2.x, w2.y, w2.z);
  c.v0 = int(w0.w);
  c.v1 = int(w1.w);
  c.v2 = int(w2.w);
  return c;
}

struct MeshHit {
  int word;  // the triangle's first word; -1: none
  real t;
};

// Deeper than any BVH the build makes (triangle_bvh.cpp: at most 97 levels;
// a scene refuses a deeper one), so a push never overflows.
const int MESH_STACK = 100;

// The slab test with the far distance widened by 1 + 2 gamma(3) (Ize 2013,
// "Robust BVH Ray Traversal", JCGT 2(2)), as triangle_bvh.cpp does, so that
// rounding never drops a box the ray grazes; RAY_TMAX for a miss.
real meshBoxEntry(vec3 o, vec3 invD, vec4 lo, vec4 hi, real tmax) {
  vec3 t0 = (vec3(lo.x, lo.y, lo.z) - o) * invD;
  vec3 t1 = (vec3(hi.x, hi.y, hi.z) - o) * invD;
  vec3 tn = min(t0, t1);
  vec3 tf = max(t0, t1) * real(1.0000004);
  real enter = max(max(tn.x, tn.y), max(tn.z, real(0)));
  real leave = min(min(tf.x, tf.y), min(tf.z, tmax));
  return enter <= leave ? enter : RAY_TMAX;
}

// The nearest triangle of the mesh at header word `header` with
// RAY_TMIN < t < tmax, or at t == tmax with a word below `best` (the hit so
// far: a lower triangle word wins a tie, whichever mesh holds it, so that a
// pixel's candidate list, walked in another order, finds the same triangle;
// primitive numbers lie below every triangle word); else `best` and tmax.
// A stack rather than scene.glsl's stackless walk: the
// nearer child goes first, so that hits found there cull the farther
// subtree, which on a mesh of many triangles saves most of the boxes.
MeshHit traceMesh(int header, vec3 o, vec3 d, real tmax, int best) {
  MeshHit h;
  h.word = best;
  h.t = tmax;
  vec4 hw = sceneWord(header);
  int nodes = int(hw.x);
  int firstNode = int(hw.y);
  int firstTri = int(hw.z);
  if (nodes == 0) return h;
  ShearedRay sr = shearedRay(d);
  vec3 invD = vec3(safeInverse(d.x), safeInverse(d.y), safeInverse(d.z));
  int stack[MESH_STACK];
  int sp = 0;
  vec4 r0 = sceneWord(firstNode);
  vec4 r1 = sceneWord(firstNode + 1);
  int node = meshBoxEntry(o, invD, r0, r1, h.t) != RAY_TMAX ? 0 : -1;
  while (node >= 0) {
    vec4 n0 = sceneWord(firstNode + 2 * node);
    vec4 n1 = sceneWord(firstNode + 2 * node + 1);
    int offset = int(n0.w);
    int count = int(n1.w);
    int next = -1;
    if (count > 0) {
      for (int k = 0; k < count; k++) {
        int w = firstTri + 3 * (offset + k);
        TriangleCorners tri = triangleAt(w);
        real t = intersectTriangle(sr, o, tri.p0, tri.p1, tri.p2);
        // Equal t: the lower word, so the answer does not depend on the order of the walk.
        if (t > real(0) && (t < h.t || (t == h.t && w < h.word))) {
          h.t = t;
          h.word = w;
        }
      }
    } else {
      int left = node + 1;
      vec4 l0 = sceneWord(firstNode + 2 * left);
      vec4 l1 = sceneWord(firstNode + 2 * left + 1);
      vec4 q0 = sceneWord(firstNode + 2 * offset);
      vec4 q1 = sceneWord(firstNode + 2 * offset + 1);
      real tl = meshBoxEntry(o, invD, l0, l1, h.t);
      real tr = meshBoxEntry(o, invD, q0, q1, h.t);
      if (tl != RAY_TMAX && tr != RAY_TMAX) {
        next = tl <= tr ? left : offset;
        stack[sp] = tl <= tr ? offset : left;
        sp++;
      } else if (tl != RAY_TMAX) {
        next = left;
      } else if (tr != RAY_TMAX) {
        next = offset;
      }
    }
    if (next < 0 && sp > 0) {
      sp--;
      next = stack[sp];
    }
    node = next;
  }
  return h;
}

// Header word of mesh primitive `index`.
int meshHeaderOf(int index) { return int(sceneWord(scenePrimWord(index) + 2).w); }

#endif

// The nearest hit among the unbounded primitives (planes), which every ray
// tests before the BVH's.
Hit unboundedHit(vec3 o, vec3 d) {
  Hit hit;
  hit.prim = -1;
  hit.t = RAY_TMAX;
  vec4 header = sceneWord(0);
  int bvhPrims = int(header.x);
  int unbounded = int(header.w);
  for (int i = 0; i < unbounded; i++) {
    real t = intersectPrim(loadPrim(bvhPrims + i), o, d);
    if (t > real(0) && t < hit.t) {
      hit.t = t;
      hit.prim = bvhPrims + i;
    }
  }
  return hit;
}

// Whether the ray enters BVH node (n0, n1)'s box before tmax.
bool nodeEntered(vec3 o, vec3 invD, vec4 n0, vec4 n1, real tmax) {
  return intersectBox(o, invD, vec3(n0.x, n0.y, n0.z), vec3(n1.x, n1.y, n1.z), tmax) != RAY_TMAX;
}

// hit, or the node's primitive's when the ray entered its box (inBox) and
// meets the primitive nearer: a leaf's test, in traceScene's walk and in
// the kernel's tile lists alike.
Hit withLeafHit(Hit hit, vec3 o, vec3 d, vec4 n1, bool inBox) {
  int prim = int(n1.w) - 1;  // -1: interior
  if (inBox && prim >= 0) {
    real t = intersectPrim(loadPrim(prim), o, d);
    if (t > real(0) && t < hit.t) {
      hit.t = t;
      hit.prim = prim;
    }
#ifdef SHIMMER_MESHES
    if (isMesh(loadPrim(prim))) {
      MeshHit m = traceMesh(meshHeaderOf(prim), o, d, hit.t, hit.prim);
      hit.t = m.t;
      hit.prim = m.word;
    }
#endif
  }
  return hit;
}

vec3 inverseDirection(vec3 d) { return vec3(safeInverse(d.x), safeInverse(d.y), safeInverse(d.z)); }

Hit traceScene(vec3 o, vec3 d) {
  Hit hit = unboundedHit(o, d);
  int nodes = int(sceneWord(0).y);
  if (nodes == 0) return hit;
  vec3 invD = inverseDirection(d);
  // One straight-line body per node (leaves hold one primitive): a SIMD CPU
  // driver runs every statement of the body for all lanes anyway, and a nested
  // per-leaf loop cost twice as much.
  int node = 0;
  while (node < nodes) {
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    bool inBox = nodeEntered(o, invD, n0, n1, hit.t);
    hit = withLeafHit(hit, o, d, n1, inBox);
    node = inBox && int(n1.w) - 1 < 0 ? node + 1 : int(n0.w);
  }
  return hit;
}

// ---- per-pixel candidate lists -----------------------------------------------
// Every sample of a pixel leaves the pinhole's origin inside the cone around
// the pixel-centre ray that holds the pixel's four corner rays. The reference
// finds the primitives that cone touches once per pixel and tests only those
// per sample: one BVH walk instead of N x N. A conservative test keeps the
// result exactly that of traceScene (same primitives, same order, same ties).
// A mesh's triangles are candidates too: the pixel walks the mesh's BVH once
// with the pyramid of its corner rays (tighter than the cone for the long,
// thin and large triangles of meshes), and its samples test the triangles it
// kept instead of each walking the BVH.

#ifdef SHIMMER_MESHES
// A ray through a torus crosses four surfaces, each a triangle or two in a
// pixel: a mesh kernel keeps eight.
const int PIXEL_CANDIDATES = 8;  // more: the pixel's samples walk the BVH
#else
const int PIXEL_CANDIDATES = 4;  // more: the pixel's samples walk the BVH
#endif

struct PixelCone {
  vec3 o;
  vec3 axis;
  real cosA;  // half-angle, slightly widened
  real sinA;
#ifdef SHIMMER_MESHES
  // The pyramid of the pixel's corner rays, which holds every sample ray (a
  // camera ray's direction is affine in the pixel position before it is
  // normalised): its side planes through o, normals pointing in.
  vec3 side0;
  vec3 side1;
  vec3 side2;
  vec3 side3;
  vec3 corner0;  // the corner rays' unit directions
  vec3 corner1;
  vec3 corner2;
  vec3 corner3;
#endif
};

#ifdef SHIMMER_MESHES
// The inward normal of the side plane through o spanned by corner rays a, b.
vec3 pyramidSide(vec3 a, vec3 b, vec3 axis) {
  vec3 n = normalize(cross(a, b));
  return dot(n, axis) >= real(0) ? n : -n;
}
#endif

PixelCone pixelCone(Camera c, ivec2 px) {
  vec2 base = vec2(real(px.x), real(px.y));
  PixelCone k;
  k.o = c.pos;
  k.axis = cameraRay(c, base + vec2(real(0.5), real(0.5))).d;
  // The corner rays' unit directions, for the cone and the mesh pyramid.
  vec3 d00 = cameraRay(c, base).d;
  vec3 d10 = cameraRay(c, base + vec2(real(1), real(0))).d;
  vec3 d01 = cameraRay(c, base + vec2(real(0), real(1))).d;
  vec3 d11 = cameraRay(c, base + vec2(real(1), real(1))).d;
  real cosA = min(min(dot(k.axis, d00), dot(k.axis, d10)), min(dot(k.axis, d01), dot(k.axis, d11)));
  // Widen by 1e-3 relative plus an absolute floor: rounding in the corner
  // rays must never drop a primitive a sample ray hits.
  k.sinA = min(sqrt(max(real(1) - cosA * cosA, real(0))) * real(1.001) + real(1e-5), real(1));
  k.cosA = sqrt(real(1) - k.sinA * k.sinA);
#ifdef SHIMMER_MESHES
  k.side0 = pyramidSide(d00, d10, k.axis);
  k.side1 = pyramidSide(d10, d11, k.axis);
  k.side2 = pyramidSide(d11, d01, k.axis);
  k.side3 = pyramidSide(d01, d00, k.axis);
  k.corner0 = d00;
  k.corner1 = d10;
  k.corner2 = d11;
  k.corner3 = d01;
#endif
  return k;
}

// A lower bound of the distance from point q to the cone: rho cosA - z sinA
// (rho: distance from the axis, z: depth along it) equals that distance where
// the nearest cone point is on the mantle and is below it elsewhere (Cauchy-
// Schwarz), so "<= r" never rejects a sphere of radius r the cone touches.
real coneDistanceBound(PixelCone k, vec3 q) {
  vec3 v = q - k.o;
  real z = dot(v, k.axis);
  real rho = length(v - k.axis * z);
  return rho * k.cosA - z * k.sinA;
}

// r plus a margin for rounding, relative to the distance from the eye.
real relaxedRadius(real r, real distance) { return r * real(1.0001) + real(1e-5) * distance; }

bool coneTouchesSphere(PixelCone k, vec3 c, real r) {
  return coneDistanceBound(k, c) <= relaxedRadius(r, length(c - k.o));
}

// Capsule a-b: the segment point nearest the axis line bounds rho from below
// and the deeper end bounds z from above.
bool coneTouchesCapsule(PixelCone k, vec3 a, vec3 b, real r) {
  vec3 w = a - k.o;
  vec3 u = b - a;
  vec3 wp = w - k.axis * dot(w, k.axis);
  vec3 up = u - k.axis * dot(u, k.axis);
  real uu = dot(up, up);
  real s = uu > real(1e-20) ? clamp(-dot(wp, up) / uu, real(0), real(1)) : real(0);
  real rho = length(wp + up * s);
  real zMax = max(dot(w, k.axis), dot(b - k.o, k.axis));
  return rho * k.cosA - zMax * k.sinA <= relaxedRadius(r, max(length(w), length(b - k.o)));
}

bool coneTouchesPrim(PixelCone k, Prim p) {
  if (isSphere(p)) return coneTouchesSphere(k, p.a, p.radius);
  if (isCapsule(p)) return coneTouchesCapsule(k, p.a, p.b, p.radius);
  return true;  // planes are unbounded
}

struct PixelCandidates {
  int count;  // > PIXEL_CANDIDATES: too many, trace the whole scene
  int id0;    // -1: empty slot
  int id1;
  int id2;
  int id3;
  Prim p0;
  Prim p1;
  Prim p2;
  Prim p3;
#ifdef SHIMMER_MESHES
  int id4;
  int id5;
  int id6;
  int id7;
  Prim p4;
  Prim p5;
  Prim p6;
  Prim p7;
#endif
};

PixelCandidates withCandidate(PixelCandidates l, int id) {
  if (l.count == 0) l.id0 = id;
  if (l.count == 1) l.id1 = id;
  if (l.count == 2) l.id2 = id;
  if (l.count == 3) l.id3 = id;
#ifdef SHIMMER_MESHES
  if (l.count == 4) l.id4 = id;
  if (l.count == 5) l.id5 = id;
  if (l.count == 6) l.id6 = id;
  if (l.count == 7) l.id7 = id;
#endif
  l.count = l.count + 1;
  return l;
}

#ifdef SHIMMER_MESHES
// Slack of the pyramid tests relative to the distance from the eye: rounding
// in the corner rays and the cross products must never drop a triangle a
// sample ray hits (a pixel spans about 1e-2 radians; this widens it by ~1 %).
const real PYRAMID_SLACK = real(1e-4);

// Whether point q lies outside the side plane of normal n by more than the slack.
bool outsideSide(PixelCone k, vec3 n, vec3 q) {
  vec3 v = q - k.o;
  return dot(n, v) < -PYRAMID_SLACK * length(v);
}

// Whether the box lo..hi lies wholly outside one side plane of the pixel's
// pyramid (its corner farthest along the normal is outside).
bool boxOutsidePyramid(PixelCone k, vec3 lo, vec3 hi) {
  vec3 c = (lo + hi) * real(0.5);
  vec3 e = (hi - lo) * real(0.5);
  real slack = PYRAMID_SLACK * (length(c - k.o) + length(e));
  return dot(k.side0, c - k.o) + dot(abs(k.side0), e) < -slack ||
         dot(k.side1, c - k.o) + dot(abs(k.side1), e) < -slack ||
         dot(k.side2, c - k.o) + dot(abs(k.side2), e) < -slack ||
         dot(k.side3, c - k.o) + dot(abs(k.side3), e) < -slack;
}

// Whether the pixel's corner rays all lie outside the plane through the eye
// and the triangle's edge a-b, on the side away from its corner c: then no
// ray of the pixel meets the triangle. (The rays that meet a triangle form
// the cone of these three planes; two convex cones with one apex are apart
// exactly when a face plane of one of them separates them, so with the side
// planes this is the separating-axis test of the two cones.)
bool pyramidOutsideEdge(PixelCone k, vec3 a, vec3 b, vec3 c) {
  vec3 m = cross(a - k.o, b - k.o);
  real len = length(m);
  real side = dot(m, c - k.o);
  // The eye near the triangle's plane: the edge decides nothing.
  if (!(abs(side) > PYRAMID_SLACK * len * length(c - k.o))) return false;
  m = (side > real(0) ? m : -m) / len;
  return dot(m, k.corner0) < -PYRAMID_SLACK && dot(m, k.corner1) < -PYRAMID_SLACK &&
         dot(m, k.corner2) < -PYRAMID_SLACK && dot(m, k.corner3) < -PYRAMID_SLACK;
}

// Whether no ray of the pixel meets the triangle: its three corners lie
// outside one side plane of the pyramid, or the pyramid outside one edge's plane.
bool triangleOutsidePyramid(PixelCone k, vec3 a, vec3 b, vec3 c) {
  return (outsideSide(k, k.side0, a) && outsideSide(k, k.side0, b) && outsideSide(k, k.side0, c)) ||
         (outsideSide(k, k.side1, a) && outsideSide(k, k.side1, b) && outsideSide(k, k.side1, c)) ||
         (outsideSide(k, k.side2, a) && outsideSide(k, k.side2, b) && outsideSide(k, k.side2, c)) ||
         (outsideSide(k, k.side3, a) && outsideSide(k, k.side3, b) && outsideSide(k, k.side3, c)) ||
         pyramidOutsideEdge(k, a, b, c) || pyramidOutsideEdge(k, b, c, a) || pyramidOutsideEdge(k, c, a, b);
}

// l with the triangles of the mesh at `header` that the pixel's pyramid may
// hold, walked as traceMesh walks (any order would do: triangles tie by
// word). Stops once the list is past PIXEL_CANDIDATES.
PixelCandidates withMeshCandidates(PixelCandidates l, PixelCone k, int header) {
  vec4 hw = sceneWord(header);
  int nodes = int(hw.x);
  int firstNode = int(hw.y);
  int firstTri = int(hw.z);
  int stack[MESH_STACK];
  int sp = 0;
  int node = nodes > 0 ? 0 : -1;
  while (node >= 0 && l.count <= PIXEL_CANDIDATES) {
    vec4 n0 = sceneWord(firstNode + 2 * node);
    vec4 n1 = sceneWord(firstNode + 2 * node + 1);
    int next = -1;
    if (!boxOutsidePyramid(k, vec3(n0.x, n0.y, n0.z), vec3(n1.x, n1.y, n1.z))) {
      int offset = int(n0.w);
      int count = int(n1.w);
      if (count > 0) {
        for (int i = 0; i < count; i++) {
          int w = firstTri + 3 * (offset + i);
          TriangleCorners tri = triangleAt(w);
          if (!triangleOutsidePyramid(k, tri.p0, tri.p1, tri.p2)) l = withCandidate(l, w);
        }
      } else {
        next = node + 1;
        stack[sp] = offset;
        sp++;
      }
    }
    if (next < 0 && sp > 0) {
      sp--;
      next = stack[sp];
    }
    node = next;
  }
  return l;
}
#endif

// The unbounded primitives, which every pixel's list starts with.
PixelCandidates unboundedCandidates() {
  PixelCandidates l;
  l.count = 0;
  l.id0 = -1;
  l.id1 = -1;
  l.id2 = -1;
  l.id3 = -1;
#ifdef SHIMMER_MESHES
  l.id4 = -1;
  l.id5 = -1;
  l.id6 = -1;
  l.id7 = -1;
#endif
  vec4 header = sceneWord(0);
  int bvhPrims = int(header.x);
  int unbounded = int(header.w);
  for (int i = 0; i < unbounded; i++) l = withCandidate(l, bvhPrims + i);
  return l;
}

// Whether the cone reaches BVH node (n0, n1)'s box (its bounding sphere).
bool coneReachesNode(PixelCone k, vec4 n0, vec4 n1) {
  vec3 lo = vec3(n0.x, n0.y, n0.z);
  vec3 hi = vec3(n1.x, n1.y, n1.z);
  return coneTouchesSphere(k, (lo + hi) * real(0.5), length(hi - lo) * real(0.5));
}

// l with the node's primitive when the cone reaches its box (inCone) and the
// primitive: a leaf's step, in pixelCandidates' walk and in the kernel's tile
// lists alike.
PixelCandidates withLeafCandidate(PixelCandidates l, PixelCone k, vec4 n1, bool inCone) {
  int prim = int(n1.w) - 1;
  if (inCone && prim >= 0 && coneTouchesPrim(k, loadPrim(prim))) l = withCandidate(l, prim);
#ifdef SHIMMER_MESHES
  // A mesh is no candidate (its hits are triangles): its triangles in the pixel's pyramid are.
  if (inCone && prim >= 0 && isMesh(loadPrim(prim))) l = withMeshCandidates(l, k, meshHeaderOf(prim));
#endif
  return l;
}

// The candidates' primitives loaded once, for every sample of the pixel.
PixelCandidates withLoadedPrims(PixelCandidates l) {
  l.p0 = loadPrim(max(l.id0, 0));
  l.p1 = loadPrim(max(l.id1, 0));
  l.p2 = loadPrim(max(l.id2, 0));
  l.p3 = loadPrim(max(l.id3, 0));
#ifdef SHIMMER_MESHES
  l.p4 = loadPrim(max(l.id4, 0));
  l.p5 = loadPrim(max(l.id5, 0));
  l.p6 = loadPrim(max(l.id6, 0));
  l.p7 = loadPrim(max(l.id7, 0));
#endif
  return l;
}

PixelCandidates pixelCandidates(PixelCone k) {
  PixelCandidates l = unboundedCandidates();
  int nodes = int(sceneWord(0).y);
  int node = 0;
  while (node < nodes) {
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    bool inCone = coneReachesNode(k, n0, n1);
    l = withLeafCandidate(l, k, n1, inCone);
    node = inCone && int(n1.w) - 1 < 0 ? node + 1 : int(n0.w);
  }
  return withLoadedPrims(l);
}

#ifdef SHIMMER_MESHES
// nearerHit for the triangle at word `id` (p its loaded corners 0 and 1).
Hit nearerTriangleHit(Hit h, Prim p, int id, vec3 o, vec3 d) {
  vec4 w2 = sceneWord(id + 2);
  real t = intersectTriangle(shearedRay(d), o, p.a, p.b, vec3(w2.x, w2.y, w2.z));
  // A tie between triangles goes to the lower word, as in traceMesh.
  if (t > real(0) && (t < h.t || (t == h.t && id < h.prim))) {
    h.t = t;
    h.prim = id;
  }
  return h;
}
#endif

Hit nearerHit(Hit h, Prim p, int id, vec3 o, vec3 d) {
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return nearerTriangleHit(h, p, id, o, d);
#endif
  real t = intersectPrim(p, o, d);
  if (t > real(0) && t < h.t) {
    h.t = t;
    h.prim = id;
  }
  return h;
}

// Candidate `id`'s primitive, already loaded (id must be in the list).
Prim candidatePrim(PixelCandidates l, int id) {
  if (id == l.id1) return l.p1;
  if (id == l.id2) return l.p2;
  if (id == l.id3) return l.p3;
#ifdef SHIMMER_MESHES
  if (id == l.id4) return l.p4;
  if (id == l.id5) return l.p5;
  if (id == l.id6) return l.p6;
  if (id == l.id7) return l.p7;
#endif
  return l.p0;
}

// traceScene for a ray of the pixel whose candidates l holds; only when
// l.count <= PIXEL_CANDIDATES (the caller branches once per pixel, not per ray).
Hit traceCandidates(PixelCandidates l, vec3 o, vec3 d) {
  Hit h;
  h.prim = -1;
  h.t = RAY_TMAX;
  // A loop to the pixel's count rather than four tests: a SIMD batch stops
  // at its lanes' largest count, usually 1-2 (plane, sphere).
  for (int i = 0; i < l.count; i++) {
#ifdef SHIMMER_MESHES
    Prim p = i < 4 ? (i == 0 ? l.p0 : (i == 1 ? l.p1 : (i == 2 ? l.p2 : l.p3)))
                   : (i == 4 ? l.p4 : (i == 5 ? l.p5 : (i == 6 ? l.p6 : l.p7)));
    int id = i < 4 ? (i == 0 ? l.id0 : (i == 1 ? l.id1 : (i == 2 ? l.id2 : l.id3)))
                   : (i == 4 ? l.id4 : (i == 5 ? l.id5 : (i == 6 ? l.id6 : l.id7)));
#else
    Prim p = i == 0 ? l.p0 : (i == 1 ? l.p1 : (i == 2 ? l.p2 : l.p3));
    int id = i == 0 ? l.id0 : (i == 1 ? l.id1 : (i == 2 ? l.id2 : l.id3));
#endif
    h = nearerHit(h, p, id, o, d);
  }
  return h;
}

// ---- surface attributes -----------------------------------------------------

#ifdef SHIMMER_MESHES
// ---- triangle attributes --------------------------------------------------------
// A point q of a triangle's plane (or off it: a neighbour pixel's ray continued
// onto the plane past the edge) has barycentrics (b0, b1, b2) that interpolate
// the corners' attributes linearly, past the edges too, as a rasterizer's
// helper lanes extrapolate them.

TriangleCorners triangleCorners(Prim p) { return triangleAt(int(p.radius)); }

// The gradients of b1 and b2 in the plane (b0's is minus their sum): the
// barycentrics of q are b1 = g1.(q - p0), b2 = g2.(q - p0).
struct BarycentricGradient {
  vec3 g1;
  vec3 g2;
};

BarycentricGradient barycentricGradient(TriangleCorners c) {
  vec3 e1 = c.p1 - c.p0;
  vec3 e2 = c.p2 - c.p0;
  real d00 = dot(e1, e1);
  real d01 = dot(e1, e2);
  real d11 = dot(e2, e2);
  real inv = real(1) / (d00 * d11 - d01 * d01);
  BarycentricGradient g;
  g.g1 = (e1 * d11 - e2 * d01) * inv;
  g.g2 = (e2 * d00 - e1 * d01) * inv;
  return g;
}

vec3 barycentricsAt(TriangleCorners c, vec3 q) {
  BarycentricGradient g = barycentricGradient(c);
  real b1 = dot(g.g1, q - c.p0);
  real b2 = dot(g.g2, q - c.p0);
  return vec3(real(1) - b1 - b2, b1, b2);
}

// Their change for a move dq.
vec3 barycentricChange(TriangleCorners c, vec3 dq) {
  BarycentricGradient g = barycentricGradient(c);
  real b1 = dot(g.g1, dq);
  real b2 = dot(g.g2, dq);
  return vec3(-b1 - b2, b1, b2);
}

vec3 vertexNormal(int v) {
  vec4 w = sceneWord(v);
  return vec3(w.x, w.y, w.z);
}
vec4 vertexTangent(int v) { return sceneWord(v + 1); }
vec2 vertexUv(int v) { return vec2(sceneWord(v).w, sceneWord(v + 2).x); }

vec3 interpolate3(vec3 b, vec3 x0, vec3 x1, vec3 x2) { return x0 * b.x + x1 * b.y + x2 * b.z; }

// The interpolated vertex normal before normalisation.
vec3 triangleNormalSum(TriangleCorners c, vec3 b) {
  return interpolate3(b, vertexNormal(c.v0), vertexNormal(c.v1), vertexNormal(c.v2));
}

// The face normal turned to the side the vertex normals point to: the side
// the mesh faces (triangle_mesh.h's convention).
vec3 triangleGeometricNormal(TriangleCorners c) {
  vec3 f = cross(c.p1 - c.p0, c.p2 - c.p0);
  vec3 s = vertexNormal(c.v0) + vertexNormal(c.v1) + vertexNormal(c.v2);
  return dot(f, s) < real(0) ? -f : f;
}

vec3 triangleShadingNormal(Prim p, vec3 q) {
  TriangleCorners c = triangleCorners(p);
  return safeNormalize(triangleNormalSum(c, barycentricsAt(c, q)), safeNormalize(triangleGeometricNormal(c), vec3(real(0), real(1), real(0))));
}

// d(interpolated unit normal) for a move dq: the derivative of
// normalize(sum b_i n_i), with db linear in dq.
vec3 triangleShadingNormalDeriv(Prim p, vec3 q, vec3 dq) {
  TriangleCorners c = triangleCorners(p);
  vec3 n = triangleNormalSum(c, barycentricsAt(c, q));
  vec3 dn = triangleNormalSum(c, barycentricChange(c, dq));
  return dNormalize(n, dn);
}

vec2 triangleUv(Prim p, vec3 q) {
  TriangleCorners c = triangleCorners(p);
  vec3 b = barycentricsAt(c, q);
  return vertexUv(c.v0) * b.x + vertexUv(c.v1) * b.y + vertexUv(c.v2) * b.z;
}

// ---- Roughness textures ------------------------------------------------------
// A mesh's roughness texture (renderer/scene/scene_packing.cpp): a header
// (width, height, first texel word, 0), then per texel the factor
// (G / mean G)^2 by which the material's alpha is scaled there, four texels
// a word, row 0 at v = 0; uv repeats (glTF's default sampler). A triangle's
// vertex words name the header (0: none).
int triangleRoughnessMap(Prim p) { return int(sceneWord(int(sceneWord(int(p.radius)).w) + 2).z); }

real roughnessTexel(int first, int w, int x, int y) {
  int i = y * w + x;
  vec4 q = sceneWord(first + i / 4);
  int k = i - (i / 4) * 4;
  return k == 0 ? q.x : (k == 1 ? q.y : (k == 2 ? q.z : q.w));
}

// Texel index i (a whole number) wrapped into [0, n).
int wrapTexel(real i, int n) { return min(int(i - real(n) * floor(i / real(n))), n - 1); }

// Bilinear on level 0 at uv, texel centres at half-integers as GL samples.
real roughnessFactorAt(int header, vec2 uv) {
  vec4 hd = sceneWord(header);
  int w = int(hd.x);
  int h = int(hd.y);
  int first = int(hd.z);
  real tx = uv.x * real(w) - real(0.5);
  real ty = uv.y * real(h) - real(0.5);
  real fx = floor(tx);
  real fy = floor(ty);
  int x0 = wrapTexel(fx, w);
  int x1 = wrapTexel(fx + real(1), w);
  int y0 = wrapTexel(fy, h);
  int y1 = wrapTexel(fy + real(1), h);
  real top = mix(roughnessTexel(first, w, x0, y0), roughnessTexel(first, w, x1, y0), tx - fx);
  real bottom = mix(roughnessTexel(first, w, x0, y1), roughnessTexel(first, w, x1, y1), tx - fx);
  return mix(top, bottom, ty - fy);
}

#endif


// The normal pattern of a bumpy plane: three sine waves of height
// (bumpSlope / w) sin(w k.q + phase), so that each contributes slopes up to
// bumpSlope. Returns the height gradient (dh/dx, dh/dz).
vec2 bumpWaveDir(int i) {
  if (i == 0) return vec2(real(0.955336), real(0.295520));
  if (i == 1) return vec2(real(0.169967), real(0.985450));
  return vec2(real(-0.801144), real(0.598472));
}
real bumpWaveScale(int i) { return i == 0 ? real(1) : (i == 1 ? real(1.7) : real(2.9)); }

vec2 bumpGradient(Prim p, vec3 q) {
  vec2 g = vec2(real(0), real(0));
  for (int i = 0; i < 3; i++) {
    vec2 k = bumpWaveDir(i) * (p.bumpFreq * bumpWaveScale(i));
    g = g + normalize(k) * (p.bumpSlope * cos(k.x * q.x + k.y * q.z + real(i)));
  }
  return g;
}

// d(gradient) for a move dq of the point: the Hessian times dq.
vec2 bumpGradientDeriv(Prim p, vec3 q, vec3 dq) {
  vec2 dg = vec2(real(0), real(0));
  for (int i = 0; i < 3; i++) {
    vec2 k = bumpWaveDir(i) * (p.bumpFreq * bumpWaveScale(i));
    real s = -p.bumpSlope * sin(k.x * q.x + k.y * q.z + real(i)) * (k.x * dq.x + k.y * dq.z);
    dg = dg + normalize(k) * s;
  }
  return dg;
}

vec3 capsuleAxisPoint(Prim p, vec3 q) {
  vec3 ba = p.b - p.a;
  real h = clamp(dot(q - p.a, ba) / dot(ba, ba), real(0), real(1));
  return p.a + ba * h;
}

// The unnormalised geometric normal of p's surface continued through q, q
// anywhere (helper-lane extrapolation evaluates points off the surface).
vec3 geometricNormalDir(Prim p, vec3 q) {
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleGeometricNormal(triangleCorners(p));
#endif
  if (isSphere(p)) return q - p.a;
  if (isCapsule(p)) return q - capsuleAxisPoint(p, q);
  return vec3(real(0), real(1), real(0));
}

vec3 geometricNormalAt(Prim p, vec3 q) {
  return safeNormalize(geometricNormalDir(p, q), vec3(real(0), real(1), real(0)));
}

// d(geometric normal) for a move dq on the surface.
vec3 geometricNormalDeriv(Prim p, vec3 q, vec3 dq) {
  if (isSphere(p)) return dNormalize(q - p.a, dq);
  if (isCapsule(p)) {
    vec3 ba = p.b - p.a;
    real h = dot(q - p.a, ba) / dot(ba, ba);
    vec3 along = (h > real(0) && h < real(1)) ? ba * (dot(dq, ba) / dot(ba, ba)) : vec3(real(0), real(0), real(0));
    return dNormalize(q - capsuleAxisPoint(p, q), dq - along);
  }
  return vec3(real(0), real(0), real(0));
}


// Reference axis of the tangent frame: anisotropic roughness ax runs along
// cross(axis, n) (around a sphere's pole, around a capsule, along x on a plane).
vec3 tangentAxis(Prim p, vec3 n) {
  vec3 axis = vec3(real(0), real(1), real(0));
  if (isCapsule(p)) axis = normalize(p.b - p.a);
  if (isPlane(p)) axis = vec3(real(0), real(0), real(1));
  vec3 c = cross(axis, n);
  if (dot(c, c) < real(1e-12)) axis = vec3(real(1), real(0), real(0));
  return axis;
}

// ---- texture coordinates and normal maps ------------------------------------
// uv of each primitive, before the map's scale (docs/scenes.md):
//   plane: u, v = world distance along the tangent and bitangent (1 unit = 1);
//   sphere: u = longitude / 2 pi around +y, v = latitude from the south pole / pi;
//   capsule: u = angle around the axis / 2 pi, v = distance along the axis from a.
// u and v grow along the tangent frame's tangent and bitangent (those of
// tangentAxis), so a tangent-space normal (x, y, z) is x t + y b + z n.

struct GeometricFrame {
  vec3 t;
  vec3 b;
  vec3 n;
};

#ifdef SHIMMER_MESHES
// The interpolated tangent (xyz) and the first corner's handedness (w).
vec4 triangleTangentSum(TriangleCorners c, vec3 b) {
  vec4 t0 = vertexTangent(c.v0);
  vec3 t = interpolate3(b, vec3(t0.x, t0.y, t0.z), vec3(vertexTangent(c.v1).x, vertexTangent(c.v1).y, vertexTangent(c.v1).z),
                        vec3(vertexTangent(c.v2).x, vertexTangent(c.v2).y, vertexTangent(c.v2).z));
  return vec4(t.x, t.y, t.z, t0.w < real(0) ? real(-1) : real(1));
}

// The interpolated tangent made orthogonal to n (Gram-Schmidt), unnormalised;
// zero when the mesh has no tangents (no uv) or it runs along n.
vec3 tangentAgainst(vec3 t, vec3 n) { return t - n * dot(n, t); }

bool usableTangent(vec3 tp) { return dot(tp, tp) > real(1e-12); }

// The shading frame's tangent at q with unit normal n: the mesh's tangent
// where it has one, else the analytic default about +y (tangentAxis).
vec3 triangleShadingTangent(Prim p, vec3 q, vec3 n) {
  TriangleCorners c = triangleCorners(p);
  vec4 ts = triangleTangentSum(c, barycentricsAt(c, q));
  vec3 tp = tangentAgainst(vec3(ts.x, ts.y, ts.z), n);
  if (usableTangent(tp)) return normalize(tp);
  return normalize(cross(tangentAxis(p, n), n));
}

// Its change for a move dq with normal change dn.
vec3 triangleShadingTangentDeriv(Prim p, vec3 q, vec3 n, vec3 dq, vec3 dn) {
  TriangleCorners c = triangleCorners(p);
  vec4 ts = triangleTangentSum(c, barycentricsAt(c, q));
  vec3 t = vec3(ts.x, ts.y, ts.z);
  vec3 tp = tangentAgainst(t, n);
  if (!usableTangent(tp)) {
    vec3 axis = tangentAxis(p, n);
    return dNormalize(cross(axis, n), cross(axis, dn));
  }
  vec4 dts = triangleTangentSum(c, barycentricChange(c, dq));
  vec3 dt = vec3(dts.x, dts.y, dts.z);
  return dNormalize(tp, dt - dn * dot(n, t) - n * (dot(dn, t) + dot(n, dt)));
}

// The frame a tangent-space normal map is read in: the interpolated normal,
// the tangent along +u, and the bitangent along +v. glTF's bitangent
// w cross(N, T) points toward -v (triangle_mesh.h), so +v is its opposite.
GeometricFrame triangleMapFrame(Prim p, vec3 q) {
  TriangleCorners c = triangleCorners(p);
  vec3 b = barycentricsAt(c, q);
  GeometricFrame f;
  f.n = safeNormalize(triangleNormalSum(c, b), safeNormalize(triangleGeometricNormal(c), vec3(real(0), real(1), real(0))));
  vec4 ts = triangleTangentSum(c, b);
  vec3 tp = tangentAgainst(vec3(ts.x, ts.y, ts.z), f.n);
  f.t = usableTangent(tp) ? normalize(tp) : normalize(cross(tangentAxis(p, f.n), f.n));
  f.b = cross(f.n, f.t) * (-ts.w);
  return f;
}

#endif

GeometricFrame geometricFrame(Prim p, vec3 q) {
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleMapFrame(p, q);
#endif
  GeometricFrame f;
  f.n = geometricNormalAt(p, q);
  f.t = normalize(cross(tangentAxis(p, f.n), f.n));
  f.b = cross(f.n, f.t);
  return f;
}

// A unit vector perpendicular to the capsule axis u: the angle's zero.
vec3 capsuleZeroDirection(vec3 u) {
  vec3 ref = abs(u.x) < real(0.9) ? vec3(real(1), real(0), real(0)) : vec3(real(0), real(1), real(0));
  return normalize(cross(u, ref));
}

vec2 surfaceUv(Prim p, vec3 q) {
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleUv(p, q);
#endif
  if (isSphere(p)) {
    vec3 d = safeNormalize(q - p.a, vec3(real(0), real(1), real(0)));
    return vec2(atan(-d.z, d.x) / (real(2) * PI), real(1) - acos(clamp(d.y, real(-1), real(1))) / PI);
  }
  if (isCapsule(p)) {
    vec3 u = normalize(p.b - p.a);
    vec3 e1 = capsuleZeroDirection(u);
    vec3 e2 = cross(u, e1);
    vec3 d = q - capsuleAxisPoint(p, q);
    return vec2(atan(dot(d, e2), dot(d, e1)) / (real(2) * PI), dot(q - p.a, u));
  }
  GeometricFrame f = geometricFrame(p, q);
  return vec2(dot(q, f.t), dot(q, f.b));
}

// The period of u (spheres and capsules wrap around once per unit of u):
// quad differences of u are taken modulo it.
real surfaceUPeriod(Prim p) { return isSphere(p) || isCapsule(p) ? real(1) : real(0); }

// d uv / d q for a move along the surface: gradients of u and of v.
struct UvGradient {
  vec3 du;
  vec3 dv;
};

#ifdef SHIMMER_MESHES
// d uv / d q in the plane: u and v are linear in the barycentrics.
UvGradient triangleUvGradient(Prim p) {
  TriangleCorners c = triangleCorners(p);
  BarycentricGradient g = barycentricGradient(c);
  vec2 uv0 = vertexUv(c.v0);
  vec2 d1 = vertexUv(c.v1) - uv0;
  vec2 d2 = vertexUv(c.v2) - uv0;
  UvGradient o;
  o.du = g.g1 * d1.x + g.g2 * d2.x;
  o.dv = g.g1 * d1.y + g.g2 * d2.y;
  return o;
}
#endif

UvGradient surfaceUvGradient(Prim p, vec3 q) {
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleUvGradient(p);
#endif
  GeometricFrame f = geometricFrame(p, q);
  UvGradient g;
  g.du = f.t;
  g.dv = f.b;
  if (isSphere(p)) {
    vec3 d = q - p.a;
    real rho = max(length(vec2(d.x, d.z)), p.radius * real(1e-6));
    g.du = f.t / (real(2) * PI * rho);
    g.dv = f.b / (PI * p.radius);
  }
  if (isCapsule(p)) {
    g.du = f.t / (real(2) * PI * p.radius);
    g.dv = normalize(p.b - p.a);
  }
  return g;
}

// A tangent-space normal tn of mapped primitive p at q, in world space.
vec3 mappedNormal(Prim p, vec3 q, vec3 tn) {
  GeometricFrame f = geometricFrame(p, q);
  return safeNormalize(f.t * tn.x + f.b * tn.y + f.n * tn.z, f.n);
}

// The shading normal at q: the primitive's own (bump pattern or geometric)
// or its normal map read by filter nf.
vec3 shadingNormalFiltered(Prim p, vec3 q, NormalMapFilter nf) {
  if (isMapped(p)) return mappedNormal(p, q, normalMapNormal(nf.mode, normalMapStats(p.map, nf, surfaceUv(p, q))));
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleShadingNormal(p, q);
#endif
  if (!isBumpy(p)) return geometricNormalAt(p, q);
  vec2 g = bumpGradient(p, q);
  return normalize(vec3(-g.x, real(1), -g.y));
}

// d(shading normal) for a move dq on the surface. A mapped normal is a
// texture, not a closed form: its change is the central difference over the
// move, as the pixel's own footprint sees it.
vec3 shadingNormalDerivFiltered(Prim p, vec3 q, vec3 dq, NormalMapFilter nf) {
  if (isMapped(p)) {
    vec3 h = dq * real(0.5);
    return shadingNormalFiltered(p, q + h, nf) - shadingNormalFiltered(p, q - h, nf);
  }
#ifdef SHIMMER_MESHES
  if (isTriangle(p)) return triangleShadingNormalDeriv(p, q, dq);
#endif
  if (!isBumpy(p)) return geometricNormalDeriv(p, q, dq);
  vec2 g = bumpGradient(p, q);
  vec2 dg = bumpGradientDeriv(p, q, dq);
  return dNormalize(vec3(-g.x, real(1), -g.y), vec3(-dg.x, real(0), -dg.y));
}
