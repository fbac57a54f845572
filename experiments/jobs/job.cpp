#include "shimmer/experiments/job.h"

#include <cstdio>
#include <mutex>
#include <set>
#include <vector>

#include "shimmer/metrics/metrics_version.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

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
  if (auto it = spec.reference_spp_by_scene.find(scene); it != spec.reference_spp_by_scene.end())
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
                if (seen.insert(JobDescription(key)).second) jobs.push_back(std::move(job));
              }
  for (const ExternalSequence& sequence : spec.sequences) jobs.push_back(ExternalJob(spec, sequence));
  return jobs;
}

Result<render::RenderSettings> RenderSettingsOf(const Job& job) {
  using R = Result<render::RenderSettings>;
  render::RenderSettings s;
  auto scene = scene::LoadScene(job.scene);
  if (!scene) return Prefixed("scene", scene.failure());
  auto material = scene::ParseMaterial(job.material, scene->material);
  if (!material) return material.failure();
  const auto camera = scene::ParseCameraPath(job.camera);
  if (!camera) return R::Failure("camera: unknown camera path '" + job.camera + "'");
  const auto derivatives = shading::ParseDerivativeSource(job.derivatives);
  if (!derivatives)
    return R::Failure("derivatives: '" + job.derivatives + "' must be " + std::string(shading::kDerivativeSourceList));
  s.scene = *scene;
  s.material = *material;
  s.camera = *camera;
  s.fps = job.fps;
  s.width = job.width;
  s.height = job.height;
  s.frames = job.frames;
  s.variant = job.variant;
  s.param_overrides.assign(job.params.begin(), job.params.end());
  if (!job.variant_hash.empty()) {
    // The id promised this content: a file edited since the spec was read
    // would store other numbers under it.
    auto user = shading::LoadUserVariant(job.variant_file);
    if (!user) return user.failure();
    if (user->content_hash != job.variant_hash)
      return R::Failure(job.variant_file + ": the variant file changed since the spec was read; run again");
    s.variant_file = job.variant_file;
  }
  s.derivatives = *derivatives;
  if (Status v = render::ValidateSettings(s); !v) return v.failure();
  return s;
}

Result<render::RenderSettings> ReferenceSettingsOf(const Job& job) {
  auto reference = RenderSettingsOf(AsNone(job));
  if (!reference) return reference.failure();
  reference->reference_spp = job.reference.spp;
  reference->reference_tolerance = job.reference.tolerance;
  reference->reference_replicates = job.reference.replicates;
  return reference;
}

SceneTraits TraitsOfScene(const scene::Scene& scene) {
  SceneTraits traits;
  traits.known = true;
  traits.sg_light = scene.light.type == shading::LightType::kSg;
  traits.sg_sharpness = traits.sg_light ? scene.light.radius : 0.0;
  traits.normal_maps = (scene::SceneFeatures(scene) & shading::kSceneNormalMaps) != 0;
  traits.meshes = (scene::SceneFeatures(scene) & shading::kSceneMeshes) != 0;
  traits.geometry_class = scene.geometry_class;
  return traits;
}

json JobSources::ToJson() const {
  json j = {{"kernel", test.kernel},
            {"inputs", test.inputs},
            {"reference_kernel", reference.kernel},
            {"reference_inputs", reference.inputs},
            {"metrics", metrics}};
  if (scene.known) {
    j["scene"] = {{"sg_light", scene.sg_light}, {"normal_maps", scene.normal_maps}, {"sg_sharpness", scene.sg_sharpness}};
    // Written only where set, so that the traits of analytic scenes read as before.
    if (scene.meshes) j["scene"]["meshes"] = true;
    if (!scene.geometry_class.empty()) j["scene"]["geometry_class"] = scene.geometry_class;
  }
  return j;
}

JobSources JobSources::FromJson(const json& j) {
  JobSources s;
  if (!j.is_object()) return s;
  s.test = {j.value("kernel", std::string()), j.value("inputs", std::string())};
  s.reference = {j.value("reference_kernel", std::string()), j.value("reference_inputs", std::string())};
  s.metrics = j.value("metrics", std::string());
  if (const auto it = j.find("scene"); it != j.end() && it->is_object()) {
    s.scene.known = true;
    s.scene.sg_light = it->value("sg_light", false);
    s.scene.normal_maps = it->value("normal_maps", false);
    s.scene.sg_sharpness = it->value("sg_sharpness", 0.0);
    s.scene.meshes = it->value("meshes", false);
    s.scene.geometry_class = it->value("geometry_class", std::string());
  }
  return s;
}

namespace {

Result<render::RenderFingerprint> ReferenceFingerprint(const Job& job) {
  auto reference = ReferenceSettingsOf(job);
  if (!reference) return reference.failure();
  auto fingerprint = render::FingerprintRender(*reference);
  if (!fingerprint) return Prefixed("reference", fingerprint.failure());
  return fingerprint;
}

Result<JobSources> ComputeSources(const Job& job) {
  JobSources sources;
  sources.metrics = MetricsVersionOf(job);
  if (job.external) return sources;
  auto test = RenderSettingsOf(job);
  if (!test) return test.failure();
  auto fingerprint = render::FingerprintRender(*test);
  if (!fingerprint) return fingerprint.failure();
  sources.test = *fingerprint;
  sources.scene = TraitsOfScene(test->scene);
  auto reference = ReferenceFingerprint(job);
  if (!reference) return reference.failure();
  sources.reference = *reference;
  return sources;
}

struct SourcesMemo {
  std::mutex mutex;
  std::map<std::string, Result<JobSources>> sources;  // by the job's JSON
};
SourcesMemo& Memo() {
  static auto* memo = new SourcesMemo;  // leaked: jobs are looked up until exit
  return *memo;
}

json DescriptionJson(const Job& job) {
  json j = job.ToJson();
  if (job.external) {
    // Where the frames lie moves no number; what they hold does.
    j["external"].erase("test");
    j["external"].erase("reference");
    j.erase("reference_spp"), j.erase("reference_tolerance"), j.erase("reference_replicates");
    return j;
  }
  j.erase("variant_file");  // where the file is moves no number; its content (variant_hash) does
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
  return j;
}

json ReferenceDescription(const Job& job) {
  return {{"scene", job.scene},
          {"material", job.material},
          {"camera", job.camera},
          {"width", job.width},
          {"height", job.height},
          {"frames", job.frames},
          {"fps", job.fps},
          {"reference_spp", job.reference.spp},
          {"reference_tolerance", job.reference.tolerance},
          {"reference_replicates", job.reference.replicates}};
}

json FingerprintJson(const render::RenderFingerprint& f) { return {{"kernel", f.kernel}, {"inputs", f.inputs}}; }

// nlohmann objects are key-sorted: the dump is canonical.
std::string Hash(const json& j) { return Fnv1a64Hex(j.dump()); }

// A row's metrics version from the two code versions: the sparkle code's
// only where the job computes sparkle statistics.
std::string MetricsVersionFrom(const Job& job, std::string_view core, std::string_view sparkles) {
  std::string version(core);
  if (job.metrics.sparkle_threshold > 0) version += "+sparkles:" + std::string(sparkles);
  return version;
}

}  // namespace

std::string MetricsVersionOf(const Job& job) {
  return MetricsVersionFrom(job, metrics::MetricsCodeVersion(), metrics::SparkleCodeVersion());
}

// The metrics code of commit 3e90d26, the last before the split: all of it
// hashed to `before`; without the sparkle statistics, to `core`; they alone, to `sparkles`.
const MetricsVersionSplit kMetricsVersionSplit = {"f7c6fc8c154db46e", "e9101a0d4dc05f76", "96718ce91922da87"};

bool MeasuredByTodaysMetrics(std::string_view stored, const Job& job, std::string_view core_now,
                             std::string_view sparkles_now, const MetricsVersionSplit& split) {
  if (stored == MetricsVersionFrom(job, core_now, sparkles_now)) return true;
  const bool sparkles = job.metrics.sparkle_threshold > 0;
  return stored == split.before && core_now == split.core && (!sparkles || sparkles_now == split.sparkles);
}

bool Rekeyable(const Job& job, const json& stored_sources, const JobSources& now) {
  if (stored_sources.is_null()) return false;  // from before per-kernel ids: run once more
  const JobSources stored = JobSources::FromJson(stored_sources);
  return WhyRerun(job, stored, now) == std::vector<std::string>{"metrics version changed"} &&
         MeasuredByTodaysMetrics(stored.metrics, job, metrics::MetricsCodeVersion(), metrics::SparkleCodeVersion());
}

Result<JobSources> SourcesOf(const Job& job) {
  const std::string key = job.ToJson().dump();
  {
    std::lock_guard lock(Memo().mutex);
    if (auto it = Memo().sources.find(key); it != Memo().sources.end()) return it->second;
  }
  auto sources = ComputeSources(job);  // unlocked: compiling a kernel takes a while
  std::lock_guard lock(Memo().mutex);
  return Memo().sources.emplace(key, std::move(sources)).first->second;
}

void ForgetSources() {
  std::lock_guard lock(Memo().mutex);
  Memo().sources.clear();
}

std::string JobDescription(const Job& job) { return DescriptionJson(job).dump(); }

std::string JobIdFrom(const Job& job, const JobSources& sources) {
  if (job.external) return Hash({{"job", DescriptionJson(job)}, {"metrics", sources.metrics}});
  return Hash({{"job", DescriptionJson(job)},
               {"render", FingerprintJson(sources.test)},
               {"reference", ReferenceIdFrom(job, sources)},
               {"metrics", sources.metrics}});
}

std::string FramesIdFrom(const Job& job, const JobSources& sources) {
  return Hash({{"job", DescriptionJson(job)}, {"render", FingerprintJson(sources.test)}});
}

std::string ReferenceIdFrom(const Job& job, const JobSources& sources) {
  if (job.external) return Hash({{"external_reference", job.external->reference_hash}});
  return Hash({{"shot", ReferenceDescription(job)}, {"render", FingerprintJson(sources.reference)}});
}

namespace {

// A job that does not resolve keeps an id (its description marked so): it
// fails when run, and the runner reports why under that id.
JobSources SourcesOrUnresolved(const Job& job) {
  auto sources = SourcesOf(job);
  if (sources) return *sources;
  JobSources unresolved;
  unresolved.test.kernel = unresolved.reference.kernel = "unresolved";
  return unresolved;
}

}  // namespace

std::string JobId(const Job& job) { return JobIdFrom(job, SourcesOrUnresolved(job)); }
std::string FramesId(const Job& job) { return FramesIdFrom(job, SourcesOrUnresolved(job)); }
std::string ReferenceId(const Job& job) {
  JobSources sources = SourcesOrUnresolved(job);
  // A variant that does not resolve leaves its shot's reference as it is.
  if (sources.reference.kernel == "unresolved")
    if (auto reference = ReferenceFingerprint(job)) sources.reference = *reference;
  return ReferenceIdFrom(job, sources);
}

std::vector<std::string> WhyRerun(const Job& job, const JobSources& before, const JobSources& now) {
  std::vector<std::string> why;
  if (before.test.kernel != now.test.kernel) why.push_back("kernel of `" + job.variant + "` changed");
  if (before.test.inputs != now.test.inputs) why.push_back("scene, camera or parameter content changed");
  if (before.reference.kernel != now.reference.kernel || before.reference.inputs != now.reference.inputs)
    why.push_back("reference changed");
  if (before.metrics != now.metrics) why.push_back("metrics version changed");
  return why;
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
