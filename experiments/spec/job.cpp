#include "shimmer/experiments/job.h"

#include <cstdio>
#include <set>
#include <vector>

#include "shimmer/renderer/shading.h"

namespace shimmer::experiments {

using nlohmann::json;

json Job::ToJson() const {
  json j = {{"scene", scene},
          {"material", material},
          {"camera", camera},
          {"variant", variant},
          {"params", params},
          {"derivatives", derivatives},
          {"width", width},
          {"height", height},
          {"frames", frames},
          {"fps", fps},
          {"reference_spp", reference.spp},
          {"reference_tolerance", reference.tolerance},
          {"reference_replicates", reference.replicates},
          {"highlight_mask", metrics.highlight_mask},
          {"highlight_threshold", metrics.highlight_threshold},
          {"segment", metrics.segment}};
  // Only jobs that measure sparkles carry it, so other jobs' ids stay as they were.
  if (metrics.sparkle_threshold > 0) j["sparkle_threshold"] = metrics.sparkle_threshold;
  // Only user variants carry these: the ids of built-in jobs stay as they were.
  if (!variant_hash.empty()) {
    j["variant_file"] = variant_file;
    j["variant_hash"] = variant_hash;
  }
  if (external)
    j["external"] = {{"test", external->test},
                     {"reference", external->reference},
                     {"test_hash", external->test_hash},
                     {"reference_hash", external->reference_hash},
                     {"ms_per_frame", external->ms_per_frame},
                     {"device", external->device}};
  return j;
}

Job Job::FromJson(const json& j) {
  Job job;
  job.scene = j.at("scene");
  job.material = j.at("material");
  job.camera = j.at("camera");
  job.variant = j.at("variant");
  job.params = j.at("params").get<std::map<std::string, double>>();
  job.derivatives = j.at("derivatives");
  job.width = j.at("width");
  job.height = j.at("height");
  job.frames = j.at("frames");
  job.fps = j.at("fps");
  job.reference.spp = j.at("reference_spp");
  job.reference.tolerance = j.at("reference_tolerance");
  // Rows from before replicates existed were measured against one N x N pattern.
  job.reference.replicates = j.value("reference_replicates", 1);
  job.metrics.highlight_mask = j.at("highlight_mask");
  job.metrics.highlight_threshold = j.at("highlight_threshold");
  job.metrics.segment = j.at("segment");
  job.metrics.sparkle_threshold = j.value("sparkle_threshold", 0.0);
  job.variant_file = j.value("variant_file", std::string());
  job.variant_hash = j.value("variant_hash", std::string());
  if (const auto e = j.find("external"); e != j.end() && e->is_object()) {
    ExternalFrames f;
    f.test = e->at("test");
    f.reference = e->at("reference");
    f.test_hash = e->at("test_hash");
    f.reference_hash = e->at("reference_hash");
    f.ms_per_frame = e->value("ms_per_frame", 0.0);
    f.device = e->value("device", std::string());
    job.external = f;
  }
  return job;
}

namespace {

// Every combination of one value per swept parameter.
std::vector<std::map<std::string, double>> ParameterGrid(const std::map<std::string, std::vector<double>>& sweeps) {
  std::vector<std::map<std::string, double>> grid{{}};
  for (const auto& [name, values] : sweeps) {
    std::vector<std::map<std::string, double>> next;
    for (const auto& partial : grid)
      for (double v : values) {
        auto point = partial;
        point[name] = v;
        next.push_back(std::move(point));
      }
    grid = std::move(next);
  }
  return grid;
}

}  // namespace

Job SpecJob(const Spec& spec, const std::string& scene, const std::string& material, const std::string& camera,
            const std::string& variant, const std::map<std::string, double>& params, const std::string& derivatives) {
  Job job;
  job.scene = scene;
  job.material = material;
  job.camera = camera;
  job.variant = variant;
  job.params = params;
  job.derivatives = derivatives;
  job.width = spec.width;
  job.height = spec.height;
  job.frames = spec.frames;
  job.fps = spec.fps;
  job.reference = spec.reference;
  if (auto it = spec.reference_spp_by_material.find(material); it != spec.reference_spp_by_material.end())
    job.reference.spp = it->second;
  job.metrics = spec.metrics;
  if (auto it = spec.user_variants.find(variant); it != spec.user_variants.end()) {
    job.variant_file = it->second->file;
    job.variant_hash = it->second->content_hash;
    for (const shading::UserParam& p : it->second->params) job.params.emplace(p.name, p.default_value);
  }
  return job;
}

Job ExternalJob(const Spec& spec, const ExternalSequence& sequence) {
  Job job;
  job.scene = sequence.scene;
  job.material = sequence.material;
  job.camera = sequence.camera;
  job.variant = sequence.label;
  job.derivatives = kExternalDerivatives;
  job.width = sequence.width;
  job.height = sequence.height;
  job.frames = sequence.frames;
  job.fps = sequence.fps > 0 ? sequence.fps : spec.fps;
  job.metrics = spec.metrics;
  job.external = sequence.files;
  return job;
}

Job AsNone(const Job& job) {
  Job none = job;
  none.variant = "none";
  none.params.clear();
  none.variant_file.clear();
  none.variant_hash.clear();
  return none;
}

bool ReadsDerivatives(const std::string& variant) {
  auto name = shading::ParseVariantName(variant);
  return !name || name->reads_derivatives();
}

std::vector<Job> ExpandJobs(const Spec& spec) {
  std::vector<Job> jobs;
  // A job two groups share is run once, where it first appears. A variant
  // that reads no derivatives is the same job under every source: its key
  // leaves the source out, so that a group with other sources adds no second
  // `none` of a shot.
  std::set<std::string> seen;
  for (const ShotGroup& group : AllGroups(spec))
    for (const std::string& scene : group.scenes)
      for (const std::string& material : group.materials)
        for (const std::string& camera : group.cameras)
          for (const VariantSweep& variant : group.variants)
            for (const auto& params : ParameterGrid(variant.params))
              for (const std::string& derivatives : group.derivatives) {
                const bool reads = ReadsDerivatives(variant.name);
                if (!reads && derivatives != group.derivatives.front()) continue;
                Job job = SpecJob(spec, scene, material, camera, variant.name, params, derivatives);
                Job key = job;
                if (!reads) key.derivatives.clear();
                if (seen.insert(JobId(key)).second) jobs.push_back(std::move(job));
              }
  for (const ExternalSequence& sequence : spec.sequences) jobs.push_back(ExternalJob(spec, sequence));
  return jobs;
}

std::string CoreVersionOf(std::span<const std::pair<std::string_view, std::string_view>> sources,
                          std::string_view root) {
  // The files the render kernel compiles: `root` and what it #includes,
  // transitively. A file that is embedded but not yet included (a library
  // no variant calls) renders no pixel, so it moves no job id.
  std::set<std::string_view> reached{root};
  std::vector<std::string_view> pending{root};
  while (!pending.empty()) {
    const std::string_view name = pending.back();
    pending.pop_back();
    for (const auto& [file, text] : sources) {
      if (file != name) continue;
      std::size_t at = 0;
      constexpr std::string_view kInclude = "#include \"";
      while ((at = text.find(kInclude, at)) != std::string_view::npos) {
        at += kInclude.size();
        const std::size_t end = text.find('"', at);
        if (end == std::string_view::npos) break;
        const std::string_view included = text.substr(at, end - at);
        if (reached.insert(included).second) pending.push_back(included);
      }
    }
  }
  std::string all;
  for (const auto& [name, text] : sources)
    if (reached.count(name)) all.append(name).append(text);
  return Fnv1a64Hex(all);
}

std::string ShadingCoreVersion() {
  static const std::string version = CoreVersionOf(shading::GlslSources(), "core.glsl");
  return version;
}

std::string JobId(const Job& job) { return JobIdForCore(job, ShadingCoreVersion()); }

std::string JobIdForCore(const Job& job, std::string_view core_version) {
  json j = job.ToJson();
  if (job.external) {
    // Where the frames lie moves no number; what they hold does.
    j["external"].erase("test");
    j["external"].erase("reference");
    j.erase("reference_spp"), j.erase("reference_tolerance"), j.erase("reference_replicates");
    return Fnv1a64Hex(j.dump());
  }
  j["core"] = core_version;
  j.erase("variant_file");  // where the file is moves no number; its content (variant_hash) does
  // Defaults live in the C++ catalogue, not in the GLSL the core version
  // hashes: the id holds every parameter the variant reads, resolved, so a
  // default spelled out in a spec is the same job and a changed default is not.
  if (const shading::VariantInfo* info = shading::FindVariant(job.variant)) {
    const std::vector<std::pair<std::string, double>> overrides(job.params.begin(), job.params.end());
    // Jobs come from validated specs; one that does not resolve (it will
    // fail when run) keeps its parameters as given.
    if (const auto p = shading::ResolveParams(*info, overrides)) {
      json values = json::object();
      for (const shading::ParamInfo& param : info->params)
        values[std::string(param.name)] = shading::ParamValue(*p, param.name);
      j["params"] = values;
    }
  }
  return Fnv1a64Hex(j.dump());  // nlohmann objects are key-sorted: canonical
}

std::string ReferenceId(const Job& job) {
  if (job.external) return Fnv1a64Hex(json{{"external_reference", job.external->reference_hash}}.dump());
  json j = {{"scene", job.scene},
            {"material", job.material},
            {"camera", job.camera},
            {"width", job.width},
            {"height", job.height},
            {"frames", job.frames},
            {"fps", job.fps},
            {"reference_spp", job.reference.spp},
            {"reference_tolerance", job.reference.tolerance},
            {"reference_replicates", job.reference.replicates},
            {"core", ShadingCoreVersion()}};
  return Fnv1a64Hex(j.dump());
}

bool ParseShard(const std::string& text, int* index, int* count) {
  int i = 0, n = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d/%d%c", &i, &n, &tail) != 2) return false;
  if (n < 1 || i < 0 || i >= n) return false;
  *index = i;
  *count = n;
  return true;
}

std::vector<Job> ShardOf(const std::vector<Job>& jobs, int index, int count) {
  std::vector<Job> out;
  for (std::size_t k = 0; k < jobs.size(); ++k)
    if (int(k % count) == index) out.push_back(jobs[k]);
  return out;
}

}  // namespace shimmer::experiments
