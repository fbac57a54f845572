// The JSON helpers spec parsing shares (spec.cpp, fit_spec.cpp): one
// exception type that names the key of the first problem, and readers of
// lists, numbers and counts that throw it.
#pragma once

#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/core/json_file.h"
#include "shimmer/core/number_text.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"

namespace shimmer::experiments::spec_json {

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
inline int LineAt(std::string_view text, std::size_t pos) {
  return 1 + int(std::count(text.begin(), text.begin() + std::ptrdiff_t(pos), '\n'));
}

// The 1-based line of the first `"key"` in the text at or after `from`, or 0 when absent.
inline int LineOfKey(std::string_view text, const std::string& key, std::size_t from = 0) {
  const std::string needle = "\"" + key + "\"";
  const auto pos = text.find(needle, from);
  if (pos == std::string_view::npos) return 0;
  return LineAt(text, pos);
}

// Where element `index` of the array after the first `"array"` key starts,
// or npos. The text is valid JSON (it parsed); only strings need care.
inline std::size_t ElementOffset(std::string_view text, const std::string& array, int index) {
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
inline auto InGroup(int index, const std::string& field, Parse&& parse, const char* array = "groups") {
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

inline void RejectUnknownKeys(const json& object, const std::set<std::string>& known, const std::string& where) {
  for (const auto& [key, value] : object.items()) {
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw SpecError{key, "unknown key" + (where.empty() ? "" : " in " + where) + " (expected one of: " + list + ")"};
    }
  }
}

inline std::vector<std::string> StringList(const json& j, const std::string& key) {
  if (!j.is_array()) throw SpecError{key, "must be an array of strings"};
  std::vector<std::string> out;
  for (const json& v : j) {
    if (!v.is_string()) throw SpecError{key, "must be an array of strings, found " + v.dump()};
    out.push_back(v.get<std::string>());
  }
  if (out.empty()) throw SpecError{key, "is empty: the experiment would have no jobs"};
  return out;
}

inline double Number(const json& j, const std::string& key) {
  if (!j.is_number()) throw SpecError{key, "must be a number, found " + j.dump()};
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw SpecError{key, "must be finite"};
  return v;
}

// Every count is bounded, so that no spec can ask for work that never ends
// or memory that is never there; the limit is in the message.
inline int PositiveInt(const json& j, const std::string& key, int max_value) {
  if (!j.is_number_integer() || j.get<long long>() <= 0 || j.get<long long>() > max_value)
    throw SpecError{key, "must be an integer in 1.." + std::to_string(max_value) + ", found " + Quote(j)};
  return j.get<int>();
}

// A spec's name names its directories (runs/<name>/...): one path component.
inline void CheckName(const std::string& name) {
  if (name.empty() || name.size() > 64) throw SpecError{"name", "must be 1 to 64 characters"};
  if (name.front() == '.' ||
      name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") != std::string::npos)
    throw SpecError{"name",
                    "must be letters, digits, '.', '_' or '-', not starting with '.' (it names the run's "
                    "directory), found " +
                        Quote(json(name))};
}

inline shading::DerivativeSource Derivatives(const json& j, const std::string& key) {
  const auto source = j.is_string() ? shading::ParseDerivativeSource(j.get<std::string>()) : std::nullopt;
  if (!source) throw SpecError{key, "must be " + std::string(shading::kDerivativeSourceList) + ", found " + Quote(j)};
  return *source;
}

inline void CheckCamera(const std::string& c) {
  if (!scene::ParseCameraPath(c)) {
    std::string list;
    for (auto n : scene::CameraPathNames()) list += (list.empty() ? "" : ", ") + std::string(n);
    throw SpecError{c, "unknown camera path (" + list + ")"};
  }
}

inline std::vector<std::string> Scenes(const json& j) {
  std::vector<std::string> scenes = StringList(j, "scenes");
  for (const std::string& scene : scenes) {
    const auto loaded = scene::LoadScene(scene);
    if (!loaded) throw SpecError{scene, loaded.error()};
  }
  return scenes;
}

inline std::vector<std::string> Materials(const json& j) {
  std::vector<std::string> materials = StringList(j, "materials");
  for (const std::string& m : materials) {
    const auto parsed = scene::ParseMaterial(m, {});
    if (!parsed) throw SpecError{m, parsed.error()};
  }
  return materials;
}

inline std::vector<std::string> Cameras(const json& j) {
  std::vector<std::string> cameras = StringList(j, "cameras");
  for (const std::string& c : cameras) CheckCamera(c);
  return cameras;
}

// The derivative sources by their canonical names.
inline std::vector<std::string> DerivativeSources(const json& j) {
  std::vector<std::string> sources = StringList(j, "derivatives");
  for (std::string& d : sources) d = std::string(shading::DerivativeSourceName(Derivatives(d, "derivatives")));
  return sources;
}

// A list of numbers, or {"from", "to", "steps", "scale": "linear|log"}.
inline std::vector<double> ParameterValues(const json& j, const std::string& key) {
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

// The "fit" section's entries (fit_spec.cpp).
FitConfig ParseFit(const nlohmann::json& f, const Spec& spec);

}  // namespace shimmer::experiments::spec_json
