// The triangle BVH: a binned SAH build (Wald 2007, "On fast Construction of
// SAH-based Bounding Volume Hierarchies"; the cost model of pbrt-v4's
// BVHAggregate), flattened depth first, and a closest-hit traversal.
#include "shimmer/renderer/triangle_bvh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace shimmer::scene {

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
// pbrt-v4's gamma(3) = 3 eps / (1 - 3 eps), eps = half float's epsilon: the
// relative error bound of a slab distance, by which a box's far distance is
// widened so that rounding never culls a box the ray enters (Ize 2013,
// "Robust BVH Ray Traversal", JCGT 2(2)).
constexpr float kMachineEpsilon = std::numeric_limits<float>::epsilon() * 0.5f;
constexpr float kFarSlack = 1 + 2 * (3 * kMachineEpsilon / (1 - 3 * kMachineEpsilon));
// Below this depth the build splits at the median: on pathological inputs
// SAH splits can peel off one triangle at a time, and halving bounds the
// depth, and so the traversal stack: depth <= kSahDepth + 32.
constexpr int kSahDepth = 64;
constexpr int kMaxDepth = kSahDepth + 33;

struct Box {
  glm::vec3 lo{kInfinity}, hi{-kInfinity};

  void Grow(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void Grow(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  float Area() const {
    const glm::vec3 d = hi - lo;
    return d.x < 0 ? 0 : 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
};

struct Item {
  Box box;
  glm::vec3 centroid;
  std::uint32_t triangle = 0;
};

struct Split {
  int axis = -1;  // -1: none found
  int plane = 0;  // items in bins below it go left
  float cost = kInfinity;
  float lo = 0, scale = 0;

  int Bin(const Item& item, int bins) const {
    return std::min(bins - 1, static_cast<int>((item.centroid[axis] - lo) * scale));
  }
};

int LongestAxis(const Box& b) {
  const glm::vec3 d = b.hi - b.lo;
  return d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
}

class Builder {
 public:
  Builder(std::vector<Item> items, const BvhBuildOptions& options)
      : items_(std::move(items)),
        options_(options),
        bin_box_(options.bins),
        bin_count_(options.bins),
        right_cost_(options.bins) {
    nodes_.reserve(items_.size() / 2 + 1);
  }

  // The subtree of items [begin, end), appended depth first; its index.
  std::uint32_t Node(std::size_t begin, std::size_t end, int depth) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    depth_ = std::max(depth_, depth);
    Box box, centroids;
    for (std::size_t i = begin; i < end; ++i) {
      box.Grow(items_[i].box);
      centroids.Grow(items_[i].centroid);
    }
    nodes_[index].lo = box.lo;
    nodes_[index].hi = box.hi;
    const std::size_t n = end - begin;
    const Split split = n > 1 && depth < kSahDepth ? FindSplit(begin, end, centroids, box) : Split{};
    // pbrt-v4: a leaf costs one test per triangle; a split 1/2 plus the
    // area-weighted tests below it.
    if (n <= static_cast<std::size_t>(options_.max_leaf_triangles) && (n == 1 || split.cost >= n)) {
      nodes_[index].offset = static_cast<std::uint32_t>(begin);
      nodes_[index].count = static_cast<std::uint32_t>(n);
      return index;
    }
    std::size_t mid;
    if (split.axis >= 0) {
      const auto it = std::partition(items_.begin() + begin, items_.begin() + end,
                                     [&](const Item& item) { return split.Bin(item, options_.bins) < split.plane; });
      mid = static_cast<std::size_t>(it - items_.begin());
    } else {
      mid = MedianSplit(begin, end, centroids);
    }
    Node(begin, mid, depth + 1);
    const std::uint32_t right = Node(mid, end, depth + 1);
    nodes_[index].offset = right;
    return index;
  }

  std::vector<Item>& items() { return items_; }
  std::vector<BvhNode>& nodes() { return nodes_; }
  int depth() const { return depth_; }

 private:
  // Wald 2007: the centroids binned along the longest axis of their bounds,
  // then every plane between bins costed by two sweeps.
  Split FindSplit(std::size_t begin, std::size_t end, const Box& centroids, const Box& box) {
    Split split;
    const int axis = LongestAxis(centroids);
    const float extent = centroids.hi[axis] - centroids.lo[axis];
    if (!(extent > 0)) return split;
    const int bins = options_.bins;
    split.axis = axis;
    split.lo = centroids.lo[axis];
    split.scale = bins / extent;
    if (!std::isfinite(split.scale)) return Split{};  // a denormal extent: no plane separates in float
    std::fill(bin_box_.begin(), bin_box_.end(), Box{});
    std::fill(bin_count_.begin(), bin_count_.end(), 0);
    std::vector<Box>& bin_box = bin_box_;
    std::vector<std::size_t>& bin_count = bin_count_;
    std::vector<float>& right_cost = right_cost_;  // count * area of bins [plane, bins)
    for (std::size_t i = begin; i < end; ++i) {
      const int b = split.Bin(items_[i], bins);
      bin_box[b].Grow(items_[i].box);
      ++bin_count[b];
    }
    Box right;
    std::size_t right_n = 0;
    for (int b = bins - 1; b > 0; --b) {
      right.Grow(bin_box[b]);
      right_n += bin_count[b];
      right_cost[b] = right_n * right.Area();
    }
    Box left;
    std::size_t left_n = 0;
    const float area = box.Area();
    for (int plane = 1; plane < bins; ++plane) {
      left.Grow(bin_box[plane - 1]);
      left_n += bin_count[plane - 1];
      if (left_n == 0 || left_n == end - begin) continue;
      const float cost = 0.5f + (left_n * left.Area() + right_cost[plane]) / (area > 0 ? area : 1);
      if (cost < split.cost) {
        split.cost = cost;
        split.plane = plane;
      }
    }
    if (split.cost == kInfinity) split.axis = -1;
    return split;
  }

  // Halves the items by their centroids on the longest axis (by their order
  // when all centroids coincide).
  std::size_t MedianSplit(std::size_t begin, std::size_t end, const Box& centroids) {
    const std::size_t mid = (begin + end) / 2;
    const int axis = LongestAxis(centroids);
    if (centroids.hi[axis] > centroids.lo[axis])
      std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                       [axis](const Item& a, const Item& b) { return a.centroid[axis] < b.centroid[axis]; });
    return mid;
  }

  std::vector<Item> items_;
  BvhBuildOptions options_;
  std::vector<BvhNode> nodes_;
  int depth_ = 0;
  // FindSplit's scratch, one entry per bin.
  std::vector<Box> bin_box_;
  std::vector<std::size_t> bin_count_;
  std::vector<float> right_cost_;
};

// The distance at which the ray enters the box within [0, t_far], or
// infinity when it misses. A zero direction component makes its inverse
// infinite; the NaN of 0 * infinity (the origin on a slab's plane) fails both
// comparisons and so leaves the interval as it is, which is conservative.
float BoxEntry(const BvhNode& node, const glm::vec3& origin, const glm::vec3& inverse, float t_far) {
  float t_near = 0;
  for (int a = 0; a < 3; ++a) {
    float t0 = (node.lo[a] - origin[a]) * inverse[a], t1 = (node.hi[a] - origin[a]) * inverse[a];
    if (inverse[a] < 0) std::swap(t0, t1);
    t1 *= kFarSlack;
    if (t0 > t_near) t_near = t0;
    if (t1 < t_far) t_far = t1;
    if (t_near > t_far) return kInfinity;
  }
  return t_near;
}

// Nearer, or as near with a lower triangle index.
bool Better(const RayHit& hit, const std::optional<RayHit>& best) {
  return !best || hit.t < best->t || (hit.t == best->t && hit.triangle < best->triangle);
}

bool Finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

RayTriangleTest::RayTriangleTest(const glm::vec3& origin, const glm::vec3& direction) : origin_(origin) {
  const glm::vec3 a = glm::abs(direction);
  valid_ = Finite(origin) && Finite(direction) && (a.x > 0 || a.y > 0 || a.z > 0);
  if (!valid_) return;
  kz_ = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
  kx_ = (kz_ + 1) % 3;
  ky_ = (kx_ + 1) % 3;
  if (direction[kz_] < 0) std::swap(kx_, ky_);  // keeps the triangles' winding
  sx_ = direction[kx_] / direction[kz_];
  sy_ = direction[ky_] / direction[kz_];
  sz_ = 1 / direction[kz_];
}

std::optional<RayHit> RayTriangleTest::Intersect(const glm::vec3& v0, const glm::vec3& v1, const glm::vec3& v2,
                                                 float tmax) const {
  if (!valid_) return std::nullopt;
  const glm::vec3 a = v0 - origin_, b = v1 - origin_, c = v2 - origin_;
  const float ax = a[kx_] - sx_ * a[kz_], ay = a[ky_] - sy_ * a[kz_];
  const float bx = b[kx_] - sx_ * b[kz_], by = b[ky_] - sy_ * b[kz_];
  const float cx = c[kx_] - sx_ * c[kz_], cy = c[ky_] - sy_ * c[kz_];
  float u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
  if (u == 0 || v == 0 || w == 0) {  // the paper's fallback: exact products in double decide the edge
    u = static_cast<float>(static_cast<double>(cx) * by - static_cast<double>(cy) * bx);
    v = static_cast<float>(static_cast<double>(ax) * cy - static_cast<double>(ay) * cx);
    w = static_cast<float>(static_cast<double>(bx) * ay - static_cast<double>(by) * ax);
  }
  if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return std::nullopt;
  const float det = u + v + w;
  if (det == 0) return std::nullopt;
  const float t_scaled = u * (sz_ * a[kz_]) + v * (sz_ * b[kz_]) + w * (sz_ * c[kz_]);
  const float t = t_scaled / det;
  if (!(t > 0 && t < tmax)) return std::nullopt;  // NaN and infinity fail too
  const glm::vec2 barycentrics(v / det, w / det);
  if (!std::isfinite(barycentrics.x) || !std::isfinite(barycentrics.y)) return std::nullopt;
  return RayHit{t, 0, barycentrics};
}

Result<TriangleBvh> TriangleBvh::Build(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                       const BvhBuildOptions& options) {
  using R = Result<TriangleBvh>;
  if (options.bins < 2 || options.bins > 256 || options.max_leaf_triangles < 1 || options.max_leaf_triangles > 255)
    return R::Failure("BVH options: bins " + std::to_string(options.bins) + " (2 to 256), leaf size " +
                      std::to_string(options.max_leaf_triangles) + " (1 to 255)");
  if (indices.size() % 3 != 0)
    return R::Failure("BVH: " + std::to_string(indices.size()) + " indices, not a multiple of 3");
  if (indices.size() / 3 >= std::numeric_limits<std::uint32_t>::max())
    return R::Failure("BVH: " + std::to_string(indices.size() / 3) + " triangles, more than 2^32 - 2");
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!Finite(positions[i])) return R::Failure("BVH: vertex " + std::to_string(i) + " has a non-finite position");
  TriangleBvh bvh;
  std::vector<Item> items;
  items.reserve(indices.size() / 3);
  for (std::size_t k = 0; k < indices.size(); k += 3) {
    for (std::size_t c = k; c < k + 3; ++c)
      if (indices[c] >= positions.size())
        return R::Failure("BVH: index " + std::to_string(c) + " is " + std::to_string(indices[c]) +
                          ", out of range for " + std::to_string(positions.size()) + " vertices");
    const glm::vec3 &p0 = positions[indices[k]], &p1 = positions[indices[k + 1]], &p2 = positions[indices[k + 2]];
    if (ZeroAreaTriangle(p0, p1, p2)) {
      ++bvh.zero_area_;
      continue;
    }
    Item item;
    item.box.Grow(p0);
    item.box.Grow(p1);
    item.box.Grow(p2);
    item.centroid = (item.box.lo + item.box.hi) * 0.5f;
    item.triangle = static_cast<std::uint32_t>(k / 3);
    items.push_back(item);
  }
  if (items.empty()) return bvh;  // no node: every ray misses
  Builder builder(std::move(items), options);
  builder.Node(0, builder.items().size(), 0);
  bvh.nodes_ = std::move(builder.nodes());
  bvh.depth_ = builder.depth();
  bvh.order_.reserve(builder.items().size());
  bvh.vertices_.reserve(3 * builder.items().size());
  for (const Item& item : builder.items()) {
    bvh.order_.push_back(item.triangle);
    for (int c = 0; c < 3; ++c) bvh.vertices_.push_back(positions[indices[3 * std::size_t{item.triangle} + c]]);
  }
  return bvh;
}

std::optional<RayHit> TriangleBvh::Intersect(const glm::vec3& origin, const glm::vec3& direction, float tmax) const {
  const RayTriangleTest test(origin, direction);
  if (!test.valid() || nodes_.empty() || !(tmax > 0)) return std::nullopt;
  const glm::vec3 inverse = 1.0f / direction;
  std::optional<RayHit> best;
  float t_best = tmax;
  std::array<std::pair<std::uint32_t, float>, kMaxDepth + 1> stack;
  int top = 0;
  const float root = BoxEntry(nodes_[0], origin, inverse, t_best * kFarSlack);
  if (root == kInfinity) return std::nullopt;
  stack[top++] = {0, root};
  while (top > 0) {
    const auto [index, entry] = stack[--top];
    if (entry > t_best * kFarSlack) continue;  // a nearer hit was found since it was pushed
    const BvhNode& node = nodes_[index];
    if (node.count > 0) {
      for (std::uint32_t i = node.offset; i < node.offset + node.count; ++i) {
        std::optional<RayHit> hit = test.Intersect(vertices_[3 * i], vertices_[3 * i + 1], vertices_[3 * i + 2], tmax);
        if (!hit) continue;
        hit->triangle = order_[i];
        if (Better(*hit, best)) {
          best = hit;
          t_best = hit->t;
        }
      }
      continue;
    }
    const std::uint32_t left = index + 1, right = node.offset;
    const float t_left = BoxEntry(nodes_[left], origin, inverse, t_best * kFarSlack);
    const float t_right = BoxEntry(nodes_[right], origin, inverse, t_best * kFarSlack);
    // The nearer child is popped first.
    const bool left_first = t_left <= t_right;
    const std::pair<std::uint32_t, float> near{left_first ? left : right, left_first ? t_left : t_right};
    const std::pair<std::uint32_t, float> far{left_first ? right : left, left_first ? t_right : t_left};
    if (far.second != kInfinity) stack[top++] = far;
    if (near.second != kInfinity) stack[top++] = near;
  }
  return best;
}

double TriangleBvh::SahCost() const {
  if (nodes_.empty()) return 0;
  auto area = [](const BvhNode& n) {
    const glm::dvec3 d = glm::dvec3(n.hi) - glm::dvec3(n.lo);
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  };
  double cost = 0;
  for (const BvhNode& n : nodes_) cost += area(n) * (n.count > 0 ? n.count : 0.5);
  const double root = area(nodes_[0]);
  return root > 0 ? cost / root : cost;
}

std::optional<RayHit> IntersectBruteForce(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                          const glm::vec3& origin, const glm::vec3& direction, float tmax) {
  const RayTriangleTest test(origin, direction);
  std::optional<RayHit> best;
  for (std::size_t k = 0; k + 2 < indices.size(); k += 3) {
    const glm::vec3 &p0 = positions[indices[k]], &p1 = positions[indices[k + 1]], &p2 = positions[indices[k + 2]];
    if (ZeroAreaTriangle(p0, p1, p2)) continue;
    std::optional<RayHit> hit = test.Intersect(p0, p1, p2, tmax);
    if (!hit) continue;
    hit->triangle = static_cast<std::uint32_t>(k / 3);
    if (Better(*hit, best)) best = hit;
  }
  return best;
}

}  // namespace shimmer::scene
