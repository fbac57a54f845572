// Camera paths (orbit, pan, dolly, vr-jitter, static) about a scene's rig.
#include "shimmer/renderer/scene.h"

#include <cmath>

namespace shimmer::scene {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

// --- camera paths -------------------------------------------------------------

namespace {
constexpr std::pair<CameraPath, std::string_view> kCameraPaths[] = {{CameraPath::kOrbit, "orbit"},
                                                                    {CameraPath::kPan, "pan"},
                                                                    {CameraPath::kDolly, "dolly"},
                                                                    {CameraPath::kVrJitter, "vr-jitter"},
                                                                    {CameraPath::kStatic, "static"}};
}  // namespace

std::vector<std::string_view> CameraPathNames() {
  std::vector<std::string_view> names;
  for (const auto& [path, name] : kCameraPaths) names.push_back(name);
  return names;
}

std::optional<CameraPath> ParseCameraPath(std::string_view name) {
  for (const auto& [path, n] : kCameraPaths)
    if (n == name) return path;
  return std::nullopt;
}

std::string_view CameraPathName(CameraPath path) {
  for (const auto& [p, name] : kCameraPaths)
    if (p == path) return name;
  return "static";
}

namespace {
shading::CameraDesc LookAt(glm::dvec3 pos, glm::dvec3 target, double fov_y_deg, int width, int height) {
  shading::CameraDesc c;
  c.pos = pos;
  c.fwd = glm::normalize(target - pos);
  glm::dvec3 up_hint{0, 1, 0};
  if (std::abs(glm::dot(c.fwd, up_hint)) > 0.999) up_hint = {0, 0, -1};
  c.right = glm::normalize(glm::cross(c.fwd, up_hint));
  c.up = glm::cross(c.right, c.fwd);
  c.tan_half_fov_y = std::tan(fov_y_deg * kPi / 360.0);
  c.width = width;
  c.height = height;
  return c;
}

glm::dvec3 Spherical(double distance, double elevation_deg, double azimuth_deg) {
  double el = elevation_deg * kPi / 180, az = azimuth_deg * kPi / 180;
  return distance * glm::dvec3(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
}
}  // namespace

// orbit: 45 degrees per second around the target. pan: sideways at 0.1
// distance per second, looking in a fixed direction. dolly: the distance
// halves every 2 seconds (the footprint scale changes). vr-jitter: head-tracking
// tremor, sums of sines of ~0.3% of the distance and ~0.2 degrees of rotation.
shading::CameraDesc CameraAt(CameraPath path, const CameraRig& rig, int frame, double fps, int width, int height) {
  const double t = frame / fps;
  glm::dvec3 pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg);
  switch (path) {
    case CameraPath::kOrbit: {
      pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg + 45.0 * t);
      return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    }
    case CameraPath::kPan: {
      shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
      glm::dvec3 shift = c0.right * (0.1 * rig.distance * t);
      return LookAt(pos + shift, rig.target + shift, rig.fov_y_deg, width, height);
    }
    case CameraPath::kDolly: {
      pos = rig.target + Spherical(rig.distance * std::exp2(-t / 2.0), rig.elevation_deg, rig.azimuth_deg);
      return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    }
    case CameraPath::kVrJitter: {
      const double a = 0.003 * rig.distance, w = 2 * kPi;
      glm::dvec3 d{std::sin(w * 0.7 * t) + 0.5 * std::sin(w * 2.9 * t + 1.0),
                   std::sin(w * 1.3 * t + 2.0) + 0.4 * std::sin(w * 3.7 * t), std::sin(w * 0.9 * t + 0.5)};
      double yaw = 0.2 * std::sin(w * 0.5 * t + 0.3), pitch = 0.15 * std::sin(w * 1.1 * t + 1.2);
      shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
      glm::dvec3 look = c0.fwd + c0.right * std::tan(yaw * kPi / 180) + c0.up * std::tan(pitch * kPi / 180);
      glm::dvec3 p = pos + a * d;
      return LookAt(p, p + look, rig.fov_y_deg, width, height);
    }
    case CameraPath::kStatic: break;
  }
  return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
}

}  // namespace shimmer::scene
