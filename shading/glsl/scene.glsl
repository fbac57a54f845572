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
// Normal-map headers and texels follow the primitives.
// The includer provides `vec4 sceneWord(int i)` (normal_map.glsl, included
// first, declares the empty scene of stand-alone compile checks).

const int PRIM_SPHERE = 0;
const int PRIM_CAPSULE = 1;
const int PRIM_PLANE = 2;

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
#ifndef SHIMMER_SCENE_FEATURES
const int SCENE_FEATURES = SCENE_SPHERES | SCENE_CAPSULES | SCENE_PLANES | SCENE_BUMPS | SCENE_NORMAL_MAPS;
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

Prim loadPrim(int index) {
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

Hit traceScene(vec3 o, vec3 d) {
  Hit hit;
  hit.prim = -1;
  hit.t = RAY_TMAX;
  vec4 header = sceneWord(0);
  int bvhPrims = int(header.x);
  int nodes = int(header.y);
  int unbounded = int(header.w);
  for (int i = 0; i < unbounded; i++) {
    real t = intersectPrim(loadPrim(bvhPrims + i), o, d);
    if (t > real(0) && t < hit.t) {
      hit.t = t;
      hit.prim = bvhPrims + i;
    }
  }
  if (nodes == 0) return hit;
  vec3 invD = vec3(safeInverse(d.x), safeInverse(d.y), safeInverse(d.z));
  // One straight-line body per node (leaves hold one primitive): a SIMD CPU
  // driver runs every statement of the body for all lanes anyway, and a nested
  // per-leaf loop cost twice as much.
  int node = 0;
  while (node < nodes) {
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    bool inBox = intersectBox(o, invD, vec3(n0.x, n0.y, n0.z), vec3(n1.x, n1.y, n1.z), hit.t) != RAY_TMAX;
    int prim = int(n1.w) - 1;  // -1: interior
    if (inBox && prim >= 0) {
      real t = intersectPrim(loadPrim(prim), o, d);
      if (t > real(0) && t < hit.t) {
        hit.t = t;
        hit.prim = prim;
      }
    }
    node = inBox && prim < 0 ? node + 1 : int(n0.w);
  }
  return hit;
}

// ---- per-pixel candidate lists -----------------------------------------------
// Every sample of a pixel leaves the pinhole's origin inside the cone around
// the pixel-centre ray that holds the pixel's four corner rays. The reference
// finds the primitives that cone touches once per pixel and tests only those
// per sample: one BVH walk instead of N x N. A conservative test keeps the
// result exactly that of traceScene (same primitives, same order, same ties).

const int PIXEL_CANDIDATES = 4;  // more: the pixel's samples walk the BVH

struct PixelCone {
  vec3 o;
  vec3 axis;
  real cosA;  // half-angle, slightly widened
  real sinA;
};

PixelCone pixelCone(Camera c, ivec2 px) {
  vec2 base = vec2(real(px.x), real(px.y));
  PixelCone k;
  k.o = c.pos;
  k.axis = cameraRay(c, base + vec2(real(0.5), real(0.5))).d;
  real cosA = dot(k.axis, cameraRay(c, base).d);
  cosA = min(cosA, dot(k.axis, cameraRay(c, base + vec2(real(1), real(0))).d));
  cosA = min(cosA, dot(k.axis, cameraRay(c, base + vec2(real(0), real(1))).d));
  cosA = min(cosA, dot(k.axis, cameraRay(c, base + vec2(real(1), real(1))).d));
  // Widen by 1e-3 relative plus an absolute floor: rounding in the corner
  // rays must never drop a primitive a sample ray hits.
  k.sinA = min(sqrt(max(real(1) - cosA * cosA, real(0))) * real(1.001) + real(1e-5), real(1));
  k.cosA = sqrt(real(1) - k.sinA * k.sinA);
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
};

PixelCandidates withCandidate(PixelCandidates l, int id) {
  if (l.count == 0) l.id0 = id;
  if (l.count == 1) l.id1 = id;
  if (l.count == 2) l.id2 = id;
  if (l.count == 3) l.id3 = id;
  l.count = l.count + 1;
  return l;
}

PixelCandidates pixelCandidates(PixelCone k) {
  PixelCandidates l;
  l.count = 0;
  l.id0 = -1;
  l.id1 = -1;
  l.id2 = -1;
  l.id3 = -1;
  vec4 header = sceneWord(0);
  int bvhPrims = int(header.x);
  int nodes = int(header.y);
  int unbounded = int(header.w);
  for (int i = 0; i < unbounded; i++) l = withCandidate(l, bvhPrims + i);
  int node = 0;
  while (node < nodes) {
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    vec3 lo = vec3(n0.x, n0.y, n0.z);
    vec3 hi = vec3(n1.x, n1.y, n1.z);
    bool inCone = coneTouchesSphere(k, (lo + hi) * real(0.5), length(hi - lo) * real(0.5));
    int prim = int(n1.w) - 1;
    if (inCone && prim >= 0 && coneTouchesPrim(k, loadPrim(prim))) l = withCandidate(l, prim);
    node = inCone && prim < 0 ? node + 1 : int(n0.w);
  }
  l.p0 = loadPrim(max(l.id0, 0));
  l.p1 = loadPrim(max(l.id1, 0));
  l.p2 = loadPrim(max(l.id2, 0));
  l.p3 = loadPrim(max(l.id3, 0));
  return l;
}

Hit nearerHit(Hit h, Prim p, int id, vec3 o, vec3 d) {
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
    Prim p = i == 0 ? l.p0 : (i == 1 ? l.p1 : (i == 2 ? l.p2 : l.p3));
    int id = i == 0 ? l.id0 : (i == 1 ? l.id1 : (i == 2 ? l.id2 : l.id3));
    h = nearerHit(h, p, id, o, d);
  }
  return h;
}

// ---- surface attributes -----------------------------------------------------

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

GeometricFrame geometricFrame(Prim p, vec3 q) {
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

UvGradient surfaceUvGradient(Prim p, vec3 q) {
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
  if (!isBumpy(p)) return geometricNormalDeriv(p, q, dq);
  vec2 g = bumpGradient(p, q);
  vec2 dg = bumpGradientDeriv(p, q, dq);
  return dNormalize(vec3(-g.x, real(1), -g.y), vec3(-dg.x, real(0), -dg.y));
}
