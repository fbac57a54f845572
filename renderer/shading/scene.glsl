// Scene geometry of the renderer: the pinhole camera with ray differentials,
// analytic primitives (sphere, capsule, plane with a procedural normal
// pattern), their normals and normal derivatives, and a BVH walk.
//
// The scene is a flat array of vec4 words (renderer/scene/scene.cpp packs it;
// floats hold small integers exactly):
//   word 0                       (bvhPrimCount, nodeCount, firstPrimWord, unboundedPrimCount)
//   node i, words 1 + 2i, 2 + 2i (bbmin, skip), (bbmax, 8 firstPrim + primCount; 0 = interior)
//     nodes in depth-first order: an interior node's first child is the next
//     node, `skip` is the node after its subtree (a stackless walk: no local
//     arrays, which SIMD CPU drivers such as lavapipe handle slowly)
//   prim j, words firstPrimWord + 3j ..
//                                (type, radius or height, bumpSlope, bumpFrequency), (a, 0), (b, 0)
// Unbounded primitives (planes) follow the BVH's primitives and are always tested.
// The includer provides `vec4 sceneWord(int i)` and defines SHIMMER_SCENE_WORDS;
// without it (stand-alone compile checks) the scene is empty.
#ifndef SHIMMER_SCENE_WORDS
vec4 sceneWord(int i) { return vec4(real(0), real(0), real(0), real(0)); }
#endif

const int PRIM_SPHERE = 0;
const int PRIM_CAPSULE = 1;
const int PRIM_PLANE = 2;
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
};

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
  if (p.type == PRIM_SPHERE) return intersectSphere(o, d, p.a, p.radius);
  if (p.type == PRIM_CAPSULE) return intersectCapsule(o, d, p.a, p.b, p.radius);
  return intersectPlane(o, d, p.radius);
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
  int node = 0;
  while (node < nodes) {
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    int skip = int(n0.w);
    if (intersectBox(o, invD, vec3(n0.x, n0.y, n0.z), vec3(n1.x, n1.y, n1.z), hit.t) == RAY_TMAX) {
      node = skip;
      continue;
    }
    int packed = int(n1.w);
    if (packed == 0) {
      node = node + 1;
      continue;
    }
    int first = packed / 8;
    int count = packed - 8 * first;
    for (int i = first; i < first + count; i++) {
      real t = intersectPrim(loadPrim(i), o, d);
      if (t > real(0) && t < hit.t) {
        hit.t = t;
        hit.prim = i;
      }
    }
    node = skip;
  }
  return hit;
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
  if (p.type == PRIM_SPHERE) return q - p.a;
  if (p.type == PRIM_CAPSULE) return q - capsuleAxisPoint(p, q);
  return vec3(real(0), real(1), real(0));
}

vec3 geometricNormalAt(Prim p, vec3 q) {
  return safeNormalize(geometricNormalDir(p, q), vec3(real(0), real(1), real(0)));
}

// d(geometric normal) for a move dq on the surface.
vec3 geometricNormalDeriv(Prim p, vec3 q, vec3 dq) {
  if (p.type == PRIM_SPHERE) return dNormalize(q - p.a, dq);
  if (p.type == PRIM_CAPSULE) {
    vec3 ba = p.b - p.a;
    real h = dot(q - p.a, ba) / dot(ba, ba);
    vec3 along = (h > real(0) && h < real(1)) ? ba * (dot(dq, ba) / dot(ba, ba)) : vec3(real(0), real(0), real(0));
    return dNormalize(q - capsuleAxisPoint(p, q), dq - along);
  }
  return vec3(real(0), real(0), real(0));
}

vec3 shadingNormalAt(Prim p, vec3 q) {
  if (p.type != PRIM_PLANE || p.bumpSlope == real(0)) return geometricNormalAt(p, q);
  vec2 g = bumpGradient(p, q);
  return normalize(vec3(-g.x, real(1), -g.y));
}

vec3 shadingNormalDeriv(Prim p, vec3 q, vec3 dq) {
  if (p.type != PRIM_PLANE || p.bumpSlope == real(0)) return geometricNormalDeriv(p, q, dq);
  vec2 g = bumpGradient(p, q);
  vec2 dg = bumpGradientDeriv(p, q, dq);
  return dNormalize(vec3(-g.x, real(1), -g.y), vec3(-dg.x, real(0), -dg.y));
}

// Reference axis of the tangent frame: anisotropic roughness ax runs along
// cross(axis, n) (around a sphere's pole, around a capsule, along x on a plane).
vec3 tangentAxis(Prim p, vec3 n) {
  vec3 axis = vec3(real(0), real(1), real(0));
  if (p.type == PRIM_CAPSULE) axis = normalize(p.b - p.a);
  if (p.type == PRIM_PLANE) axis = vec3(real(0), real(0), real(1));
  vec3 c = cross(axis, n);
  if (dot(c, c) < real(1e-12)) axis = vec3(real(1), real(0), real(0));
  return axis;
}
