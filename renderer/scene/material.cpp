// Materials from text ("ggx:0.05", "glints:0.3,local=0.03,density=1e4",
// with optional f0 and albedo) and back.
#include "shimmer/renderer/scene.h"

#include <cmath>
#include <sstream>

#include "shimmer/core/number_text.h"

namespace shimmer::scene {

namespace {

// A glint material's defaults: a microdetail's lobe, and microdetails per
// unit area (a level-0 glint cell is 1 / sqrt(density) wide).
constexpr double kDefaultGlintAlphaL = 0.03;
constexpr double kDefaultGlintDensity = 1e4;
constexpr double kMaxGlintDensity = 1e12;

bool ParseRgb(std::string_view text, glm::dvec3* out) {
  std::vector<double> v;
  std::string s(text);
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, '/')) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (used != item.size() || !std::isfinite(x) || x < 0) return false;
    v.push_back(x);
  }
  if (v.size() == 1)
    *out = glm::dvec3(v[0]);
  else if (v.size() == 3)
    *out = {v[0], v[1], v[2]};
  else
    return false;
  return true;
}

}  // namespace

namespace {
// The whole of `text` as one finite number.
bool WholeFiniteNumber(const std::string& text, double* out) {
  std::size_t used = 0;
  try {
    *out = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used != 0 && used == text.size() && std::isfinite(*out);
}
}  // namespace

Result<shading::MaterialDesc> ParseMaterial(std::string_view spec, const shading::MaterialDesc& base) {
  using R = Result<shading::MaterialDesc>;
  const std::string usage =
      " (expected NDF:ALPHA[,ALPHA_Y][,f0=V|R/G/B][,albedo=V|R/G/B], e.g. ggx:0.05, or blinn-phong:POWER[,POWER_Y], "
      "or glints:ALPHA[,ALPHA_Y][,local=ALPHA_L][,density=N])";
  shading::MaterialDesc m = base;
  auto colon = spec.find(':');
  if (colon == std::string_view::npos) return R::Failure("material '" + std::string(spec) + "'" + usage);
  auto ndf = shading::ParseNdf(spec.substr(0, colon));
  if (!ndf)
    return R::Failure("material '" + std::string(spec) + "': NDF must be ggx, beckmann, blinn-phong or glints" + usage);
  m.ndf = *ndf;
  const bool glints = m.ndf == shading::Ndf::kGlints;
  m.glint_alpha_l = glints ? kDefaultGlintAlphaL : 0.0;
  m.glint_density = glints ? kDefaultGlintDensity : 0.0;
  // Blinn-Phong is given by its power s (seed 003), alpha^2 = 2 / (s + 2).
  const bool power = m.ndf == shading::Ndf::kBlinnPhong;
  std::vector<double> alphas;
  std::stringstream ss{std::string(spec.substr(colon + 1))};
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto eq = item.find('=');
    if (eq == std::string::npos) {
      double a = 0;
      const bool number = WholeFiniteNumber(item, &a);
      if (power) {
        if (!number || a < 0 || a > 1e8)
          return R::Failure("material '" + std::string(spec) + "': Blinn-Phong power '" + item +
                            "' must be a number in [0, 1e8]");
        a = shading::BlinnPhongAlpha(a);
      }
      if (!number || a <= 0 || a > 1)
        return R::Failure("material '" + std::string(spec) + "': roughness '" + item + "' must be a number in (0, 1]");
      if (alphas.size() == 2)
        return R::Failure("material '" + std::string(spec) + "': at most two roughness values" + usage);
      alphas.push_back(a);
      continue;
    }
    std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "local" || key == "density") {
      if (!glints)
        return R::Failure("material '" + std::string(spec) + "': '" + key + "' is a glint material's field (glints:...)");
      double v = 0;
      const bool ok = WholeFiniteNumber(value, &v) && (key == "local" ? v > 0 && v <= 1 : v > 0 && v <= kMaxGlintDensity);
      if (!ok)
        return R::Failure("material '" + std::string(spec) + "': " + key + " '" + value + "' must be a number in " +
                          (key == "local" ? "(0, 1]" : "(0, 1e12]"));
      (key == "local" ? m.glint_alpha_l : m.glint_density) = v;
      continue;
    }
    glm::dvec3 rgb;
    if (!ParseRgb(value, &rgb))
      return R::Failure("material '" + std::string(spec) + "': " + key + " expects V or R/G/B (>= 0), got '" + value +
                        "'");
    if (key == "f0") {
      if (glm::any(glm::greaterThan(rgb, glm::dvec3(1))))
        return R::Failure("material '" + std::string(spec) + "': f0 must be <= 1");
      m.f0 = rgb;
    } else if (key == "albedo") {
      m.albedo = rgb;
    } else {
      return R::Failure("material '" + std::string(spec) + "': unknown field '" + key + "'" + usage);
    }
  }
  if (alphas.empty()) return R::Failure("material '" + std::string(spec) + "': no roughness" + usage);
  m.alpha = {alphas[0], alphas.size() > 1 ? alphas[1] : alphas[0]};
  return m;
}

std::string MaterialSpec(const shading::MaterialDesc& m) {
  auto rgb = [](glm::dvec3 c) {
    std::ostringstream o;
    o.precision(6);
    if (c.x == c.y && c.y == c.z)
      o << c.x;
    else
      o << c.x << "/" << c.y << "/" << c.z;
    return o.str();
  };
  std::ostringstream o;
  o.precision(6);
  auto value = [&m](double alpha) { return m.ndf == shading::Ndf::kBlinnPhong ? shading::BlinnPhongPower(alpha) : alpha; };
  o << shading::NdfName(m.ndf) << ":" << value(m.alpha.x);
  if (m.alpha.y != m.alpha.x) o << "," << value(m.alpha.y);
  if (m.ndf == shading::Ndf::kGlints) o << ",local=" << m.glint_alpha_l << ",density=" << m.glint_density;
  o << ",f0=" << rgb(m.f0) << ",albedo=" << rgb(m.albedo);
  return o.str();
}

}  // namespace shimmer::scene
