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
#include "spec_json.h"

namespace shimmer::experiments {

namespace {

using namespace spec_json;

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

// The spec object j's "reference": the reference's samples (per material too), tolerance,
// replicates and convergence check.
void ParseReference(const json& j, Spec& s) {
  const json& r = j["reference"];
  if (!r.is_object()) throw SpecError{"reference", "must be {\"spp\": N} or {\"tolerance\": T}"};
  RejectUnknownKeys(r, {"spp", "spp_by_material", "spp_by_scene", "tolerance", "replicates", "converge"}, "reference");
  if (r.contains("spp")) s.reference.spp = PositiveInt(r["spp"], "spp", render::kMaxReferenceSpp);
  // reference.KEY: {"NAME": N} for names the spec's cross products (the top
  // level's and every group's) hold in the field `field` of.
  auto spp_by = [&](const char* key, const char* kind, const char* plural,
                    std::vector<std::string> ShotGroup::*field, std::map<std::string, int>& out) {
    if (!r.contains(key)) return;
    const json& m = r[key];
    if (!m.is_object()) throw SpecError{key, std::string("must be {\"") + kind + "\": N, ...}"};
    std::set<std::string> names;
    for (const ShotGroup& group : AllGroups(s)) names.insert((group.*field).begin(), (group.*field).end());
    for (const auto& [name, spp] : m.items()) {
      if (!names.count(name))
        throw SpecError{key, name + ": not one of the spec's " + plural +
                                 std::string(s.groups.empty() ? "" : " (nor of its groups)")};
      out[name] = PositiveInt(spp, key, render::kMaxReferenceSpp);
    }
  };
  spp_by("spp_by_material", "MATERIAL", "materials", &ShotGroup::materials, s.reference_spp_by_material);
  spp_by("spp_by_scene", "SCENE", "scenes", &ShotGroup::scenes, s.reference_spp_by_scene);
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
    if (!c.is_object()) throw SpecError{"converge", "must be {\"energy\": E, \"tv\": T, \"frame_stride\": K}"};
    RejectUnknownKeys(c, {"energy", "tv", "frame_stride"}, "reference.converge");
    if (c.contains("frame_stride"))
      s.reference.converge.frame_stride = PositiveInt(c["frame_stride"], "converge.frame_stride", render::kMaxFrames);
    if (c.contains("energy")) s.reference.converge.energy = Number(c["energy"], "converge.energy");
    if (c.contains("tv")) s.reference.converge.tv = Number(c["tv"], "converge.tv");
    if (s.reference.converge.energy <= 0 || s.reference.converge.tv <= 0)
      throw SpecError{"converge", "tolerances must be > 0"};
  }
}

// The spec object j's "benchmark": off, or its size, repetitions and precision.
void ParseBenchmark(const json& j, Spec& s) {
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

// The spec object j's "metrics": the highlight mask, the Welch segment and sparkle statistics.
void ParseMetricOptions(const json& j, Spec& s) {
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

// Counted before anything is expanded, every group's cross product
// together (before jobs two groups share are merged): a cross product can
// be astronomically large.
void CheckJobCount(const Spec& s) {
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
  if (j.contains("reference")) ParseReference(j, s);
  if (j.contains("benchmark")) ParseBenchmark(j, s);
  if (j.contains("metrics")) ParseMetricOptions(j, s);
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
  CheckJobCount(s);
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
