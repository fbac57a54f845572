#include "shimmer/experiments/spec.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shimmer/core/json_file.h"
#include "shimmer/core/number_text.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::experiments {

namespace {

using nlohmann::json;

// Validation stops at the first problem; the exception carries the key so the
// message can point at its line.
struct SpecError {
  std::string key;
  std::string problem;
  // Within groups[group]: the key is looked for from that group on, and the
  // message shows `label` ("groups[0].variants: k16-nope") instead of it.
  int group = -1;
  std::string label = {};
  std::string array = "groups";  // the list `group` indexes: "groups" or "sequences"
};

// What parsing variants needs besides the JSON: where variant files are
// looked for, and the spec whose user variants they join.
struct VariantContext {
  std::filesystem::path base;  // the spec's folder
  Spec* spec;
};

// The 1-based line of offset `pos` in the text.
int LineAt(std::string_view text, std::size_t pos) {
  return 1 + int(std::count(text.begin(), text.begin() + std::ptrdiff_t(pos), '\n'));
}

// The 1-based line of the first `"key"` in the text at or after `from`, or 0 when absent.
int LineOfKey(std::string_view text, const std::string& key, std::size_t from = 0) {
  const std::string needle = "\"" + key + "\"";
  const auto pos = text.find(needle, from);
  if (pos == std::string_view::npos) return 0;
  return LineAt(text, pos);
}

// Where element `index` of the array after the first `"array"` key starts,
// or npos. The text is valid JSON (it parsed); only strings need care.
std::size_t ElementOffset(std::string_view text, const std::string& array, int index) {
  const std::string needle = "\"" + array + "\"";
  std::size_t pos = text.find(needle);
  if (pos == std::string_view::npos) return pos;
  pos = text.find_first_not_of(" \t\r\n:", pos + needle.size());
  if (pos == std::string_view::npos || text[pos] != '[') return std::string_view::npos;
  int depth = 0, element = 0;
  bool in_string = false;
  for (std::size_t i = pos; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (depth == 1 && element == index && c != ',' && c != ']' && !std::isspace(static_cast<unsigned char>(c)))
      return i;
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      if (--depth == 0) break;
    } else if (c == ',' && depth == 1) {
      ++element;
    }
  }
  return std::string_view::npos;
}

// Runs `parse` for `field` of groups[index] (the group itself when `field` is
// empty), naming the group in what it throws: a problem with `key` reads
// "groups[index].field: key: problem", or "groups[index].field: problem" when
// the key is the field.
template <class Parse>
auto InGroup(int index, const std::string& field, Parse&& parse, const char* array = "groups") {
  try {
    return parse();
  } catch (SpecError& e) {
    if (!e.label.empty()) throw;  // named already, by a nested call
    e.array = array;
    const std::string at = std::string(array) + "[" + std::to_string(index) + "]";
    if (field.empty())
      e.label = at + (e.key.empty() ? "" : "." + e.key);
    else
      e.label = at + "." + field + (e.key.empty() || e.key == field ? "" : ": " + e.key);
    e.group = index;
    throw;
  }
}

void RejectUnknownKeys(const json& object, const std::set<std::string>& known, const std::string& where) {
  for (const auto& [key, value] : object.items()) {
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw SpecError{key, "unknown key" + (where.empty() ? "" : " in " + where) + " (expected one of: " + list + ")"};
    }
  }
}

std::vector<std::string> StringList(const json& j, const std::string& key) {
  if (!j.is_array()) throw SpecError{key, "must be an array of strings"};
  std::vector<std::string> out;
  for (const json& v : j) {
    if (!v.is_string()) throw SpecError{key, "must be an array of strings, found " + v.dump()};
    out.push_back(v.get<std::string>());
  }
  if (out.empty()) throw SpecError{key, "is empty: the experiment would have no jobs"};
  return out;
}

double Number(const json& j, const std::string& key) {
  if (!j.is_number()) throw SpecError{key, "must be a number, found " + j.dump()};
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw SpecError{key, "must be finite"};
  return v;
}

// Every count is bounded, so that no spec can ask for work that never ends
// or memory that is never there; the limit is in the message.
int PositiveInt(const json& j, const std::string& key, int max_value) {
  if (!j.is_number_integer() || j.get<long long>() <= 0 || j.get<long long>() > max_value)
    throw SpecError{key, "must be an integer in 1.." + std::to_string(max_value) + ", found " + Quote(j)};
  return j.get<int>();
}

// A spec's name names its directories (runs/<name>/...): one path component.
void CheckName(const std::string& name) {
  if (name.empty() || name.size() > 64) throw SpecError{"name", "must be 1 to 64 characters"};
  if (name.front() == '.' ||
      name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") != std::string::npos)
    throw SpecError{"name",
                    "must be letters, digits, '.', '_' or '-', not starting with '.' (it names the run's "
                    "directory), found " +
                        Quote(json(name))};
}

shading::DerivativeSource Derivatives(const json& j, const std::string& key) {
  const auto source = j.is_string() ? shading::ParseDerivativeSource(j.get<std::string>()) : std::nullopt;
  if (!source) throw SpecError{key, "must be " + std::string(shading::kDerivativeSourceList) + ", found " + Quote(j)};
  return *source;
}

void CheckCamera(const std::string& c) {
  if (!scene::ParseCameraPath(c)) {
    std::string list;
    for (auto n : scene::CameraPathNames()) list += (list.empty() ? "" : ", ") + std::string(n);
    throw SpecError{c, "unknown camera path (" + list + ")"};
  }
}

std::vector<std::string> Scenes(const json& j) {
  std::vector<std::string> scenes = StringList(j, "scenes");
  for (const std::string& scene : scenes) {
    const auto loaded = scene::LoadScene(scene);
    if (!loaded) throw SpecError{scene, loaded.error()};
  }
  return scenes;
}

std::vector<std::string> Materials(const json& j) {
  std::vector<std::string> materials = StringList(j, "materials");
  for (const std::string& m : materials) {
    const auto parsed = scene::ParseMaterial(m, {});
    if (!parsed) throw SpecError{m, parsed.error()};
  }
  return materials;
}

std::vector<std::string> Cameras(const json& j) {
  std::vector<std::string> cameras = StringList(j, "cameras");
  for (const std::string& c : cameras) CheckCamera(c);
  return cameras;
}

// The derivative sources by their canonical names.
std::vector<std::string> DerivativeSources(const json& j) {
  std::vector<std::string> sources = StringList(j, "derivatives");
  for (std::string& d : sources) d = std::string(shading::DerivativeSourceName(Derivatives(d, "derivatives")));
  return sources;
}

// A list of numbers, or {"from", "to", "steps", "scale": "linear|log"}.
std::vector<double> ParameterValues(const json& j, const std::string& key) {
  if (j.is_number()) return {Number(j, key)};
  if (j.is_array()) {
    std::vector<double> out;
    for (const json& v : j) out.push_back(Number(v, key));
    if (out.empty()) throw SpecError{key, "has no values"};
    return out;
  }
  if (!j.is_object()) throw SpecError{key, "must be a number, a list, or {\"from\", \"to\", \"steps\", \"scale\"}"};
  RejectUnknownKeys(j, {"from", "to", "steps", "scale"}, key);
  for (const char* k : {"from", "to", "steps"})
    if (!j.contains(k)) throw SpecError{key, std::string("range needs \"") + k + "\""};
  const double from = Number(j["from"], key + ".from"), to = Number(j["to"], key + ".to");
  const int steps = PositiveInt(j["steps"], key + ".steps", kMaxRangeSteps);
  if (j.contains("scale") && !j["scale"].is_string()) throw SpecError{key, "scale must be \"linear\" or \"log\""};
  const std::string scale = j.value("scale", "linear");
  if (scale != "linear" && scale != "log") throw SpecError{key, "scale must be \"linear\" or \"log\""};
  if (scale == "log" && (from <= 0 || to <= 0)) throw SpecError{key, "a log range needs from > 0 and to > 0"};
  std::vector<double> out;
  for (int i = 0; i < steps; ++i) {
    const double t = steps == 1 ? 0.0 : double(i) / (steps - 1);
    out.push_back(scale == "log" ? from * std::pow(to / from, t) : from + (to - from) * t);
  }
  return out;
}

// {"file", "name", "params"}: the file registered under its name, each
// parameter value checked against the file's declared range.
VariantSweep ParseUserVariantEntry(const json& j, const VariantContext& ctx, VariantSweep v) {
  if (!j["file"].is_string() || j["file"].get<std::string>().empty())
    throw SpecError{"file", "must be the path of a variant GLSL file (relative to the spec)"};
  const std::filesystem::path file(j["file"].get<std::string>());
  const std::string path = (file.is_absolute() ? file : ctx.base / file).lexically_normal().string();
  auto ref = AddUserVariant(ctx.spec, path, v.name);
  if (!ref) throw SpecError{"file", ref.error()};
  for (const auto& [name, values] : v.params)
    for (double x : values) {
      const std::pair<std::string, double> value{name, x};
      if (auto resolved = shading::ResolveUserParams(**ref, std::span(&value, 1)); !resolved)
        throw SpecError{name, resolved.error()};
    }
  return v;
}

VariantSweep ParseVariant(const json& j, const VariantContext& ctx) {
  VariantSweep v;
  if (j.is_string()) {
    v.name = j.get<std::string>();
  } else if (j.is_object()) {
    RejectUnknownKeys(j, {"name", "params", "file"}, "a variant");
    if (!j.contains("name") || !j["name"].is_string()) throw SpecError{"variants", "each variant needs a \"name\""};
    v.name = j["name"].get<std::string>();
    if (j.contains("params")) {
      if (!j["params"].is_object()) throw SpecError{"params", "must be an object of parameter values"};
      for (const auto& [name, values] : j["params"].items()) v.params[name] = ParameterValues(values, name);
    }
    if (j.contains("file")) return ParseUserVariantEntry(j, ctx, std::move(v));
  } else {
    throw SpecError{"variants", "entries must be a name, {\"name\", \"params\"} or {\"file\", \"name\", \"params\"}"};
  }
  if (ctx.spec->user_variants.count(v.name)) {
    if (!v.params.empty())
      throw SpecError{v.name, "a variant file's parameters are given where the file is (its {\"file\", \"name\", \"params\"} entry)"};
    return v;  // named again, e.g. in a group
  }
  const auto parsed = shading::ParseVariantName(v.name);
  if (!parsed) throw SpecError{v.name, parsed.error()};
  // supersample-N is the renderer's equal-time baseline, not a catalogue entry.
  if (parsed->kind == shading::VariantName::Kind::kSupersample) {
    if (!v.params.empty()) throw SpecError{v.name, "supersample-N takes no parameters"};
    return v;
  }
  for (const auto& [name, values] : v.params) {
    for (double x : values) {
      const std::pair<std::string, double> value{name, x};
      const auto resolved = shading::ResolveParams(*parsed->info, std::span(&value, 1));
      if (!resolved) throw SpecError{name, resolved.error()};
    }
  }
  return v;
}

std::vector<VariantSweep> Variants(const json& j, const VariantContext& ctx) {
  if (!j.is_array() || j.empty()) throw SpecError{"variants", "must be a non-empty array"};
  std::vector<VariantSweep> variants;
  for (const json& v : j) variants.push_back(ParseVariant(v, ctx));
  return variants;
}

constexpr const char* kGroupKeys = "cameras, derivatives, materials, scenes, variants";

// groups[index]: the keys it has replace the top level's.
ShotGroup ParseGroup(const json& g, int index, const ShotGroup& top, const VariantContext& ctx) {
  return InGroup(index, "", [&] {
    if (!g.is_object()) throw SpecError{"", std::string("must be an object with any of: ") + kGroupKeys};
    RejectUnknownKeys(g, {"scenes", "materials", "cameras", "variants", "derivatives"}, "");
    if (g.empty())
      throw SpecError{
          "", std::string("is empty: give at least one of ") + kGroupKeys + " (the others are the top level's)"};
    ShotGroup out = top;
    if (g.contains("scenes")) out.scenes = InGroup(index, "scenes", [&] { return Scenes(g["scenes"]); });
    if (g.contains("materials")) out.materials = InGroup(index, "materials", [&] { return Materials(g["materials"]); });
    if (g.contains("cameras")) out.cameras = InGroup(index, "cameras", [&] { return Cameras(g["cameras"]); });
    if (g.contains("variants"))
      out.variants = InGroup(index, "variants", [&] { return Variants(g["variants"], ctx); });
    if (g.contains("derivatives"))
      out.derivatives = InGroup(index, "derivatives", [&] { return DerivativeSources(g["derivatives"]); });
    return out;
  });
}

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
std::string ShownName(const json& j, const std::string& key, std::size_t max_size) {
  if (!j.is_string() || j.get<std::string>().empty() || j.get<std::string>().size() > max_size)
    throw SpecError{key, "must be a string of 1 to " + std::to_string(max_size) + " characters, found " + Quote(j)};
  const std::string text = j.get<std::string>();
  for (unsigned char c : text)
    if (c < 0x20 || c == 0x7f || c == '|' || c == '"') throw SpecError{key, "must not hold control characters, '|' or '\"'"};
  return text;
}

// Whether some cross product of the spec renders this shot.
bool RendersShot(const Spec& spec, const std::string& scene, const std::string& material, const std::string& camera) {
  for (const ShotGroup& g : AllGroups(spec)) {
    auto has = [](const std::vector<std::string>& v, const std::string& x) {
      return std::find(v.begin(), v.end(), x) != v.end();
    };
    if (has(g.scenes, scene) && has(g.materials, material) && has(g.cameras, camera)) return true;
  }
  return false;
}

// sequences[index]: {"label", "test", "reference", "shot", "fps", "cost"}.
ExternalSequence ParseSequence(const json& e, int index, const Spec& spec, const std::filesystem::path& base) {
  return InGroup(index, "", [&] {
    constexpr const char* kForm =
        "must be {\"label\", \"test\", \"reference\"} with optional \"shot\", \"fps\" and \"cost\"";
    if (!e.is_object()) throw SpecError{"", kForm};
    RejectUnknownKeys(e, {"label", "test", "reference", "shot", "fps", "cost"}, "a sequence");
    for (const char* required : {"label", "test", "reference"})
      if (!e.contains(required)) throw SpecError{"", std::string("needs \"") + required + "\" (" + kForm + ")"};
    ExternalSequence seq;
    seq.label = e["label"].is_string() ? e["label"].get<std::string>() : std::string();
    if (seq.label.empty() || seq.label.size() > 64 || seq.label.front() == '.' ||
        seq.label.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") !=
            std::string::npos)
      throw SpecError{"label", "must be 1 to 64 letters, digits, '.', '_' or '-', found " + Quote(e["label"])};
    for (const char* key : {"test", "reference"}) {
      if (!e[key].is_string() || e[key].get<std::string>().empty())
        throw SpecError{key, "must be the path of a directory of EXR frames or of a sequence.json (relative to the spec)"};
      const std::filesystem::path path(e[key].get<std::string>());
      (std::string(key) == "test" ? seq.files.test : seq.files.reference) =
          (path.is_absolute() ? path : base / path).lexically_normal().string();
    }
    if (e.contains("shot")) {
      const json& shot = e["shot"];
      if (!shot.is_object() || shot.empty())
        throw SpecError{"shot", "must be {\"scene\", \"material\", \"camera\"} (any of them)"};
      RejectUnknownKeys(shot, {"scene", "material", "camera"}, "shot");
      if (shot.contains("scene")) seq.scene = ShownName(shot["scene"], "scene", 128);
      if (shot.contains("material")) seq.material = ShownName(shot["material"], "material", 128);
      if (shot.contains("camera")) seq.camera = ShownName(shot["camera"], "camera", 128);
    }
    if (e.contains("fps")) {
      seq.fps = Number(e["fps"], "fps");
      if (seq.fps <= 0 || seq.fps > 1e6) throw SpecError{"fps", "must be > 0 and <= 1e6"};
    }
    if (e.contains("cost")) {
      const json& c = e["cost"];
      if (!c.is_object() || !c.contains("ms_per_frame") || !c.contains("device"))
        throw SpecError{"cost", "must be {\"ms_per_frame\": MS, \"device\": NAME}: the time and where it was measured"};
      RejectUnknownKeys(c, {"ms_per_frame", "device"}, "cost");
      seq.files.ms_per_frame = Number(c["ms_per_frame"], "ms_per_frame");
      if (seq.files.ms_per_frame <= 0) throw SpecError{"ms_per_frame", "must be > 0"};
      seq.files.device = ShownName(c["device"], "device", 128);
    }
    for (const ExternalSequence& other : spec.sequences)
      if (other.label == seq.label && other.scene == seq.scene && other.material == seq.material &&
          other.camera == seq.camera)
        throw SpecError{"label", "'" + seq.label + "' names two sequences of the shot " + seq.scene + " / " +
                                     seq.material + " / " + seq.camera};
    if (seq.label == "none" && RendersShot(spec, seq.scene, seq.material, seq.camera))
      throw SpecError{"label", "'none': the spec renders `none` of the shot " + seq.scene + " / " + seq.material +
                                   " / " + seq.camera + " already; give the sequence another label"};
    std::string bad_key;
    auto opened = OpenExternalSequence(std::move(seq), &bad_key);
    if (!opened) throw SpecError{bad_key, opened.error()};
    return std::move(*opened);
  }, "sequences");
}

Spec ParseSpecObject(const json& j, const std::filesystem::path& base) {
  if (!j.is_object()) throw SpecError{"", "a spec is a JSON object"};
  RejectUnknownKeys(j,
                    {"name", "scenes", "materials", "cameras", "variants", "derivatives", "groups", "size", "frames",
                     "fps", "reference", "metrics", "benchmark", "fit", "sequences"},
                    "");
  Spec s;
  if (!j.contains("name")) throw SpecError{"name", "is required"};
  // External sequences alone are a spec; the rendered cross product is all
  // or nothing.
  const char* const kCrossProduct[] = {"scenes", "materials", "cameras", "variants"};
  const bool renders = std::any_of(std::begin(kCrossProduct), std::end(kCrossProduct),
                                   [&](const char* key) { return j.contains(key); });
  if (renders || !j.contains("sequences"))
    for (const char* required : kCrossProduct)
      if (!j.contains(required))
        throw SpecError{required, j.contains("sequences") ? "is required with the other keys of the rendered cross "
                                                            "product (scenes, materials, cameras, variants)"
                                                          : "is required"};
  if (!j["name"].is_string()) throw SpecError{"name", "must be a string"};
  s.name = j["name"];
  CheckName(s.name);
  const VariantContext ctx{base, &s};
  if (renders) {
    s.scenes = Scenes(j["scenes"]);
    s.materials = Materials(j["materials"]);
    s.cameras = Cameras(j["cameras"]);
    s.variants = Variants(j["variants"], ctx);
  } else if (j.contains("groups") || j.contains("fit")) {
    throw SpecError{j.contains("groups") ? "groups" : "fit",
                    "needs the rendered cross product (scenes, materials, cameras, variants)"};
  }
  if (j.contains("derivatives")) s.derivatives = DerivativeSources(j["derivatives"]);
  if (j.contains("groups")) {
    const json& g = j["groups"];
    if (!g.is_array() || g.empty())
      throw SpecError{"groups", std::string("must be a non-empty list of objects with any of: ") + kGroupKeys};
    const ShotGroup top = AllGroups(s).front();
    for (std::size_t i = 0; i < g.size(); ++i) s.groups.push_back(ParseGroup(g[i], int(i), top, ctx));
  }
  if (j.contains("size")) {
    const json& size = j["size"];
    if (!size.is_array() || size.size() != 2) throw SpecError{"size", "must be [width, height]"};
    s.width = PositiveInt(size[0], "size", render::kMaxImageSide);
    s.height = PositiveInt(size[1], "size", render::kMaxImageSide);
    if (s.width % 2 || s.height % 2) throw SpecError{"size", "width and height must be even (2x2 quads)"};
  }
  if (j.contains("frames")) s.frames = PositiveInt(j["frames"], "frames", kMaxSpecFrames);
  if (s.frames < 2) throw SpecError{"frames", "temporal metrics need at least 2 frames"};
  if (j.contains("fps")) {
    s.fps = Number(j["fps"], "fps");
    if (s.fps <= 0 || s.fps > 1e6) throw SpecError{"fps", "must be > 0 and <= 1e6"};
  }
  if (j.contains("reference")) {
    const json& r = j["reference"];
    if (!r.is_object()) throw SpecError{"reference", "must be {\"spp\": N} or {\"tolerance\": T}"};
    RejectUnknownKeys(r, {"spp", "spp_by_material", "tolerance", "replicates", "converge"}, "reference");
    if (r.contains("spp")) s.reference.spp = PositiveInt(r["spp"], "spp", render::kMaxReferenceSpp);
    if (r.contains("spp_by_material")) {
      const json& m = r["spp_by_material"];
      if (!m.is_object()) throw SpecError{"spp_by_material", "must be {\"MATERIAL\": N, ...}"};
      std::set<std::string> materials;  // of the top level and every group
      for (const ShotGroup& group : AllGroups(s)) materials.insert(group.materials.begin(), group.materials.end());
      for (const auto& [material, spp] : m.items()) {
        if (!materials.count(material))
          throw SpecError{"spp_by_material", material + ": not one of the spec's materials" +
                                                 std::string(s.groups.empty() ? "" : " (nor of its groups)")};
        s.reference_spp_by_material[material] = PositiveInt(spp, "spp_by_material", render::kMaxReferenceSpp);
      }
    }
    if (r.contains("tolerance")) {
      s.reference.tolerance = Number(r["tolerance"], "tolerance");
      if (s.reference.tolerance <= 0 || s.reference.tolerance >= 1) throw SpecError{"tolerance", "must be in (0, 1)"};
    }
    if (r.contains("replicates")) {
      s.reference.replicates = PositiveInt(r["replicates"], "replicates", render::kMaxRounds);
      if (s.reference.replicates < 2)
        throw SpecError{"replicates", "must be at least 2 (the spread of replicates is the standard error)"};
    }
    if (r.contains("converge")) {
      const json& c = r["converge"];
      if (!c.is_object()) throw SpecError{"converge", "must be {\"energy\": E, \"tv\": T}"};
      RejectUnknownKeys(c, {"energy", "tv"}, "reference.converge");
      if (c.contains("energy")) s.reference.converge.energy = Number(c["energy"], "converge.energy");
      if (c.contains("tv")) s.reference.converge.tv = Number(c["tv"], "converge.tv");
      if (s.reference.converge.energy <= 0 || s.reference.converge.tv <= 0)
        throw SpecError{"converge", "tolerances must be > 0"};
    }
  }
  if (j.contains("benchmark")) {
    const json& b = j["benchmark"];
    if (b.is_boolean()) {
      s.benchmark.enabled = b.get<bool>();
    } else if (b.is_object()) {
      RejectUnknownKeys(b, {"size", "repetitions", "precision", "max_repetitions"}, "benchmark");
      if (b.contains("size")) {
        const json& size = b["size"];
        if (!size.is_array() || size.size() != 2) throw SpecError{"benchmark.size", "must be [width, height]"};
        s.benchmark.width = PositiveInt(size[0], "benchmark.size", render::kMaxImageSide);
        s.benchmark.height = PositiveInt(size[1], "benchmark.size", render::kMaxImageSide);
        if (s.benchmark.width % 2 || s.benchmark.height % 2)
          throw SpecError{"benchmark.size", "width and height must be even (2x2 quads)"};
      }
      if (b.contains("repetitions"))
        s.benchmark.repetitions = PositiveInt(b["repetitions"], "benchmark.repetitions", 1000);
      if (b.contains("max_repetitions"))
        s.benchmark.max_repetitions = PositiveInt(b["max_repetitions"], "benchmark.max_repetitions", 10000);
      if (b.contains("precision")) {
        s.benchmark.precision = Number(b["precision"], "benchmark.precision");
        if (!(s.benchmark.precision > 0 && s.benchmark.precision < 1))
          throw SpecError{"benchmark.precision", "must be in (0, 1): the half-width of each cost ratio's interval"};
      }
      if (s.benchmark.max_repetitions < s.benchmark.repetitions)
        throw SpecError{"benchmark.max_repetitions", "must be at least benchmark.repetitions"};
    } else {
      throw SpecError{"benchmark",
                      "must be true, false or {\"size\": [w, h], \"repetitions\": R, \"precision\": P, "
                      "\"max_repetitions\": M}"};
    }
  }
  if (j.contains("metrics")) {
    const json& m = j["metrics"];
    if (!m.is_object()) throw SpecError{"metrics", "must be an object"};
    RejectUnknownKeys(m, {"highlight_mask", "highlight_threshold", "segment", "sparkle_threshold"}, "metrics");
    if (m.contains("highlight_mask")) {
      if (!m["highlight_mask"].is_boolean()) throw SpecError{"highlight_mask", "must be true or false"};
      s.metrics.highlight_mask = m["highlight_mask"];
    }
    if (m.contains("highlight_threshold")) {
      s.metrics.highlight_threshold = Number(m["highlight_threshold"], "highlight_threshold");
      if (s.metrics.highlight_threshold <= 0) throw SpecError{"highlight_threshold", "must be > 0"};
    }
    if (m.contains("segment")) s.metrics.segment = PositiveInt(m["segment"], "segment", s.frames);
    if (m.contains("sparkle_threshold")) {
      s.metrics.sparkle_threshold = Number(m["sparkle_threshold"], "sparkle_threshold");
      if (s.metrics.sparkle_threshold < 0) throw SpecError{"sparkle_threshold", "must be >= 0 (0: no sparkle statistics)"};
    }
  }
  if (j.contains("fit")) {
    const json& f = j["fit"];
    if (f.is_object()) {
      s.fits.push_back(ParseFit(f, s));
    } else if (f.is_array() && !f.empty()) {
      for (const json& entry : f) s.fits.push_back(ParseFit(entry, s));
    } else {
      throw SpecError{"fit", "must be an object or a non-empty list of objects"};
    }
  }
  if (j.contains("sequences")) {
    const json& q = j["sequences"];
    if (!q.is_array() || q.empty())
      throw SpecError{"sequences", "must be a non-empty list of {\"label\", \"test\", \"reference\"} objects"};
    if (q.size() > std::size_t(kMaxJobs)) throw SpecError{"sequences", "at most " + std::to_string(kMaxJobs)};
    for (std::size_t i = 0; i < q.size(); ++i) s.sequences.push_back(ParseSequence(q[i], int(i), s, base));
  }
  // Counted before anything is expanded, every group's cross product
  // together (before jobs two groups share are merged): a cross product can
  // be astronomically large.
  double jobs = 0;
  for (const ShotGroup& g : AllGroups(s)) {
    double combos = 0;
    for (const VariantSweep& v : g.variants) {
      double n = 1;
      for (const auto& [name, values] : v.params) n *= double(values.size());
      combos += n;
    }
    jobs += double(g.scenes.size()) * double(g.materials.size()) * double(g.cameras.size()) * combos *
            double(g.derivatives.size());
  }
  if (jobs > double(kMaxJobs))
    throw SpecError{s.groups.empty() ? "variants" : "groups",
                    "the spec expands to " + NumberText(jobs) + " jobs" +
                        (s.groups.empty() ? "" : " (top level and groups together)") + "; at most " +
                        std::to_string(kMaxJobs) + " are supported (split it into several specs)"};
  return s;
}

}  // namespace

std::string MappedScene(const std::string& scene, const std::string& map) {
  return map.empty() ? scene : scene + "@" + map;
}

Result<Spec> ParseSpec(std::string_view text, const std::string& source) {
  auto j = ParseJson(text, source);
  if (!j) return j.failure();
  try {
    return ParseSpecObject(*j, std::filesystem::path(source).parent_path());
  } catch (const SpecError& e) {
    // In a group, the key is looked for from the group on, and the group's
    // own line stands in when it is not found there.
    const std::size_t group_at = e.group >= 0 ? ElementOffset(text, e.array, e.group) : std::string_view::npos;
    const std::size_t from = group_at == std::string_view::npos ? 0 : group_at;
    int line = e.key.empty() ? 0 : LineOfKey(text, e.key, from);
    if (!line && group_at != std::string_view::npos) line = LineAt(text, group_at);
    const std::string& shown = e.label.empty() ? e.key : e.label;
    return Result<Spec>::Failure(source + (line ? ":" + std::to_string(line) : "") + ": " +
                                 (shown.empty() ? "" : shown + ": ") + e.problem);
  } catch (const json::exception& e) {
    // A type the checks above missed; nlohmann's id prefix says nothing to a user.
    std::string what = e.what();
    if (auto close = what.find("] "); close != std::string::npos) what = what.substr(close + 2);
    return Result<Spec>::Failure(source + ": " + what);
  }
}

std::vector<ShotGroup> AllGroups(const Spec& spec) {
  std::vector<ShotGroup> all{{spec.scenes, spec.materials, spec.cameras, spec.variants, spec.derivatives}};
  all.insert(all.end(), spec.groups.begin(), spec.groups.end());
  return all;
}

Result<UserVariantRef> AddUserVariant(Spec* spec, const std::string& path, const std::string& name) {
  using R = Result<UserVariantRef>;
  // The name labels report rows and plot keys, so it is held to what a spec name may be.
  if (name.empty() || name.size() > 64 || name.front() == '.' ||
      name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") != std::string::npos)
    return R::Failure("variant file name '" + name + "': must be 1 to 64 letters, digits, '.', '_' or '-'");
  if (shading::ParseVariantName(name))
    return R::Failure("'" + name + "' is a built-in variant's name; give the variant file " + path + " its own");
  auto user = shading::LoadUserVariant(path);
  if (!user) return user.failure();
  const auto it = spec->user_variants.find(name);
  const bool same = it != spec->user_variants.end() && it->second->file == user->file &&
                    it->second->content_hash == user->content_hash;
  if (same) return it->second;  // compiled when it was first named
  if (Status compiled = render::CheckUserVariant(*user); !compiled) return compiled.failure();
  if (it != spec->user_variants.end())
    return R::Failure("two variant files are named '" + name + "': " + it->second->file + " and " + path);
  UserVariantRef ref = std::make_shared<const shading::UserVariant>(std::move(*user));
  spec->user_variants[name] = ref;
  return ref;
}

Status CheckFitVariant(const Spec& spec, const std::string& variant, const std::string& param, double lo,
                       double hi) {
  std::string names;
  if (auto it = spec.user_variants.find(variant); it != spec.user_variants.end()) {
    const shading::UserVariant& user = *it->second;
    for (const shading::UserParam& p : user.params) names += (names.empty() ? "" : ", ") + p.name;
    const shading::UserParam* p = shading::FindUserParam(user, param);
    if (!p)
      return Status::Failure("has no parameter \"" + param + "\" to fit (" + user.file + " declares " +
                             (names.empty() ? "none" : names) + ")");
    if (lo < p->lo || hi > p->hi)
      return Status::Failure("the bounds [" + NumberText(lo) + ", " + NumberText(hi) + "] leave " + param +
                             "'s declared range [" + NumberText(p->lo) + ", " + NumberText(p->hi) + "] in " +
                             user.file);
    return Ok();
  }
  const shading::VariantInfo* info = shading::FindVariant(variant);
  if (!info)
    return Status::Failure(
        "unknown variant (see `shimmer variants`); fits take catalogue variants and the spec's variant files");
  bool has = false;
  for (const shading::ParamInfo& p : info->params) {
    has = has || p.name == param;
    names += (names.empty() ? "" : ", ") + std::string(p.name);
  }
  if (!has)
    return Status::Failure("has no parameter \"" + param + "\" to fit (its parameters: " +
                           (names.empty() ? "none" : names) + ")");
  for (double bound : {lo, hi})
    if (Status s = shading::ValidateParam(param, bound); !s) return Status::Failure("bounds: " + s.error());
  // The rule the renderer applies to every job (shading/src/variant_registry.cpp), so
  // that a fit is refused here for what its renders would be refused for.
  for (const std::string& m : spec.materials)
    if (auto mismatch = shading::MaterialMismatch(*info, scene::ParseMaterial(m, {})->ndf))
      return Status::Failure(*mismatch + " (the spec lists " + m + ")");
  return Ok();
}

Result<Spec> LoadSpec(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Result<Spec>::Failure(path + ": no such spec file");
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (!in && !in.eof()) return Result<Spec>::Failure(path + ": cannot read the spec file", ErrorCode::kIo);
  return ParseSpec(buffer.str(), path);
}

}  // namespace shimmer::experiments
