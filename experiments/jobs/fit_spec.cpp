// A spec's "fit" section: the parameter (or an engine's several) to fit per
// material, its bounds, the training and held-out shots, the objective's
// weights.
#include <cmath>

#include "spec_json.h"

namespace shimmer::experiments::spec_json {

namespace {

ShotSet ParseShots(const json& j, const std::string& key) {
  if (!j.is_object()) throw SpecError{key, "must be {\"scenes\": [...], \"cameras\": [...]}"};
  RejectUnknownKeys(j, {"scenes", "cameras"}, key);
  for (const char* required : {"scenes", "cameras"})
    if (!j.contains(required)) throw SpecError{key, std::string("needs \"") + required + "\""};
  ShotSet shots;
  shots.scenes = StringList(j["scenes"], key + ".scenes");
  for (const std::string& scene : shots.scenes) {
    const auto loaded = scene::LoadScene(scene);
    if (!loaded) throw SpecError{scene, loaded.error()};
  }
  shots.cameras = StringList(j["cameras"], key + ".cameras");
  for (const std::string& c : shots.cameras) CheckCamera(c);
  return shots;
}

void ParseWeights(const json& f, FitConfig* fit);
FitConfig ParseJointFit(const json& f, const Spec& spec);

// What every fit entry has: its derivative source and its shot sets.
void ParseFitShots(const json& f, FitConfig* c) {
  if (f.contains("derivatives"))
    c->derivatives = std::string(shading::DerivativeSourceName(Derivatives(f["derivatives"], "derivatives")));
  c->train = ParseShots(f["train"], "train");
  c->validate = ParseShots(f["validate"], "validate");
}

}  // namespace


// Everything a fit could trip on later is checked here, before any render:
// bounds, the parameter, each variant having it, and NDF restrictions
// against the spec's materials.
FitConfig ParseFit(const json& f, const Spec& spec) {
  if (!f.is_object()) throw SpecError{"fit", "entries must be objects"};
  RejectUnknownKeys(
      f,
      {"variants", "param", "params", "bounds", "sweep_points", "defaults", "derivatives", "train", "validate", "weights",
       "maps", "cross_validate"},
      "fit");
  if (f.contains("params")) return ParseJointFit(f, spec);
  for (const char* required : {"variants", "param", "train", "validate"})
    if (!f.contains(required)) throw SpecError{"fit", std::string("needs \"") + required + "\""};
  if (f.contains("cross_validate")) throw SpecError{"cross_validate", "is for joint fits (\"params\")"};
  FitConfig c;
  if (!f["param"].is_string()) throw SpecError{"param", "must be a parameter name"};
  c.param = f["param"];
  c.variants = StringList(f["variants"], "variants");
  if (f.contains("bounds")) {
    const json& b = f["bounds"];
    if (!b.is_array() || b.size() != 2) throw SpecError{"bounds", "must be [lo, hi]"};
    c.lo = Number(b[0], "bounds");
    c.hi = Number(b[1], "bounds");
  }
  // The search runs on log p, so the bounds must be positive.
  if (!(c.lo > 0 && c.lo < c.hi))
    throw SpecError{"bounds", "are empty or not positive: need 0 < lo < hi, found [" + NumberText(c.lo) + ", " +
                                  NumberText(c.hi) + "]"};
  for (const std::string& name : c.variants)
    if (Status s = CheckFitVariant(spec, name, c.param, c.lo, c.hi); !s) throw SpecError{name, s.error()};
  if (f.contains("sweep_points")) c.sweep_points = PositiveInt(f["sweep_points"], "sweep_points", kMaxSweepPoints);
  if (c.sweep_points < 2) throw SpecError{"sweep_points", "must be at least 2"};
  if (f.contains("defaults")) {
    c.defaults = ParameterValues(f["defaults"], "defaults");
    for (double d : c.defaults)
      if (d <= 0) throw SpecError{"defaults", "must be positive"};
  }
  ParseFitShots(f, &c);
  if (f.contains("maps")) {
    c.maps = StringList(f["maps"], "maps");
    for (const std::string& map : c.maps)
      for (const ShotSet* shots : {&c.train, &c.validate})
        for (const std::string& scene : shots->scenes) {
          const auto loaded = scene::LoadScene(MappedScene(scene, map));
          if (!loaded) throw SpecError{"maps", loaded.error()};
        }
  }
  ParseWeights(f, &c);
  return c;
}

namespace {


void ParseWeights(const json& f, FitConfig* fit) {
  FitConfig& c = *fit;
  if (f.contains("weights")) {
    const json& w = f["weights"];
    if (!w.is_object()) throw SpecError{"weights", "must be {\"flicker\", \"spatial\", \"bias\"}"};
    RejectUnknownKeys(w, {"flicker", "spatial", "bias"}, "fit.weights");
    if (w.contains("flicker")) c.weights.flicker = Number(w["flicker"], "flicker");
    if (w.contains("spatial")) c.weights.spatial = Number(w["spatial"], "spatial");
    if (w.contains("bias")) c.weights.bias = Number(w["bias"], "bias");
    if (c.weights.flicker < 0 || c.weights.spatial < 0 || c.weights.bias < 0 ||
        c.weights.flicker + c.weights.spatial + c.weights.bias <= 0)
      throw SpecError{"weights", "must be non-negative and not all zero"};
  }
}

// A joint fit: "params" names two or more parameters, "bounds" one [lo, hi]
// per parameter (lo <= 0 is allowed: such an axis is searched linearly).
FitConfig ParseJointFit(const json& f, const Spec& spec) {
  for (const char* required : {"variants", "params", "bounds", "train", "validate"})
    if (!f.contains(required)) throw SpecError{"fit", std::string("a joint fit needs \"") + required + "\""};
  if (f.contains("param")) throw SpecError{"fit", "has both \"param\" and \"params\": one parameter or a joint fit"};
  if (f.contains("maps")) throw SpecError{"maps", "fits one parameter per map; a joint fit takes none"};
  FitConfig c;
  c.variants = StringList(f["variants"], "variants");
  c.joint_params = StringList(f["params"], "params");
  if (c.joint_params.size() < 2) throw SpecError{"params", "a joint fit needs at least two parameters"};
  for (std::size_t i = 0; i < c.joint_params.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (c.joint_params[i] == c.joint_params[k]) throw SpecError{"params", c.joint_params[i] + " is named twice"};
  const json& b = f["bounds"];
  if (!b.is_array() || b.size() != c.joint_params.size())
    throw SpecError{"bounds", "must be one [lo, hi] per parameter (" + std::to_string(c.joint_params.size()) + ")"};
  for (std::size_t i = 0; i < b.size(); ++i) {
    const std::string key = "bounds[" + std::to_string(i) + "]";
    if (!b[i].is_array() || b[i].size() != 2) throw SpecError{key, "must be [lo, hi]"};
    FitAxis axis{Number(b[i][0], key), Number(b[i][1], key)};
    if (!(axis.lo < axis.hi))
      throw SpecError{key, "is empty: need lo < hi, found [" + NumberText(axis.lo) + ", " + NumberText(axis.hi) + "]"};
    c.joint_bounds.push_back(axis);
  }
  for (const std::string& name : c.variants)
    for (std::size_t i = 0; i < c.joint_params.size(); ++i)
      if (Status s = CheckFitVariant(spec, name, c.joint_params[i], c.joint_bounds[i].lo, c.joint_bounds[i].hi); !s)
        throw SpecError{name, s.error()};
  c.sweep_points = 3;  // per axis: 3^N grid points
  if (f.contains("sweep_points")) c.sweep_points = PositiveInt(f["sweep_points"], "sweep_points", kMaxSweepPoints);
  if (c.sweep_points < 2) throw SpecError{"sweep_points", "must be at least 2"};
  if (std::pow(double(c.sweep_points), double(c.joint_params.size())) > 4096)
    throw SpecError{"sweep_points", "makes a grid of more than 4096 points"};
  c.defaults.clear();
  if (f.contains("defaults"))
    throw SpecError{"defaults", "a joint fit compares with each variant's own defaults (`shimmer variants`)"};
  ParseFitShots(f, &c);
  if (f.contains("cross_validate")) {
    if (!f["cross_validate"].is_boolean()) throw SpecError{"cross_validate", "must be true or false"};
    c.cross_validate = f["cross_validate"];
    if (c.cross_validate && c.train.scenes.size() < 2)
      throw SpecError{"cross_validate", "leaves one training scene out: it needs at least two"};
  }
  ParseWeights(f, &c);
  return c;
}

// A name a report shows as a row or a table (labels, shots): printable, bounded.

}  // namespace

}  // namespace shimmer::experiments::spec_json
