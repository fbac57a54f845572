// Jobs: one (scene, material, camera, variant with parameter values,
// derivative source) of a spec, with an id that hashes what the job runs
// (its kernel and the content it reads), so reruns skip finished work and
// redo exactly the work a change touches.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/core/content_hash.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::experiments {

struct Job {
  std::string scene;
  std::string material;
  std::string camera;
  std::string variant;
  // The values the spec sweeps, and nothing else: the defaults resolve from
  // the variant table when the job renders, and the id hashes the resolved
  // values the kernel is given (its push constants), so a default that
  // changes moves the id.
  std::map<std::string, double> params;
  std::string derivatives;
  // A user variant: its file (not part of the id: the content is) and the
  // hash of its content. Its params hold every declared parameter.
  std::string variant_file, variant_hash;
  // An external sequence's job: scene, material and camera name its shot,
  // variant is its label, derivatives is "external"; nothing is rendered.
  std::optional<ExternalFrames> external;
  int width = 0, height = 0, frames = 0;
  double fps = 0;
  ReferenceQuality reference;
  MetricOptions metrics;  // part of the id: the stored numbers depend on them

  nlohmann::json ToJson() const;
  static Job FromJson(const nlohmann::json& j);
};

// One job of the spec's resolution, frames, reference and metric options; a
// user variant's job gets its file and the declared defaults of the
// parameters `params` leaves out.
Job SpecJob(const Spec& spec, const std::string& scene, const std::string& material, const std::string& camera,
            const std::string& variant, const std::map<std::string, double>& params, const std::string& derivatives);

// The job of an external sequence: measured against its own reference, with
// the spec's metric options.
Job ExternalJob(const Spec& spec, const ExternalSequence& sequence);
inline constexpr const char* kExternalDerivatives = "external";

// The same shot and options with variant `none`: no parameters, no file.
Job AsNone(const Job& job);

// False for `none` and `supersample-N`: their pixels never read the
// derivatives, so one derivative source stands for all.
bool ReadsDerivatives(const std::string& variant);

// Each cross product of AllGroups(spec) in turn, the top level first, each
// in a deterministic order (spec order, outermost first: scene, material,
// camera, variant, parameter values, derivatives), then the spec's external
// sequences in spec order. A variant that does not
// read derivatives gets one job per shot, with its group's first source. A
// job (by JobDescription) that is there already is left out: the first one stays.
std::vector<Job> ExpandJobs(const Spec& spec);

// The render settings of a job (scene loaded, material, camera and
// derivative source parsed, the user variant file checked against the hash
// the spec read), with no device and EXR frames compressed; the error names
// what does not resolve. The runner adds its device and compression.
Result<render::RenderSettings> RenderSettingsOf(const Job& job);
// Those of its reference: `none` with the job's reference spp, tolerance and
// replicates.
Result<render::RenderSettings> ReferenceSettingsOf(const Job& job);

// What a job's frames and numbers are made of (docs/guide.md, Job
// ids): the fingerprints of its render and of its reference's render
// (render::FingerprintRender: the specialized kernel module and the bytes it
// reads) and the version of the metrics code.
// What a report needs to know of a job's scene to class its shots, kept
// with the row so that the report reads it from the store rather than
// loading scene files that may have moved or changed since (no id hashes
// it: the scene's content is in the fingerprint already).
struct SceneTraits {
  bool known = false;  // false in rows stored before traits were kept
  bool sg_light = false, normal_maps = false;
  double sg_sharpness = 0;  // the SG light's sharpness, with sg_light
  bool meshes = false;      // triangle meshes among its primitives
  std::string geometry_class;  // the scene file's geometry_class, if it names one
};

// The traits of a loaded scene.
SceneTraits TraitsOfScene(const scene::Scene& scene);

struct JobSources {
  render::RenderFingerprint test, reference;
  std::string metrics;
  SceneTraits scene;
  nlohmann::json ToJson() const;
  static JobSources FromJson(const nlohmann::json& j);  // empty fields where `j` lacks them
};
// The metrics version a job's row carries (JobSources::metrics): the
// metrics code's, and the sparkle statistics' code where the job computes
// them, so that a change to the sparkle statistics re-measures the rows
// that have them and no other.
std::string MetricsVersionOf(const Job& job);

// Rows measured before the sparkle statistics had a version of their own
// carry the version of all the metrics code of that time, `before`. That
// same code's non-sparkle part hashes to `core` and its sparkle part to
// `sparkles`. So a stored row of `before` was measured by today's code when
// today's metrics code hashes to `core` and, for a row with sparkle
// statistics, today's sparkle code to `sparkles`: `shimmer run` re-keys such
// a row rather than measuring it again. The first edit of that code ends the
// equivalence, and rows of `before` are then measured once more.
struct MetricsVersionSplit {
  std::string_view before, core, sparkles;
};
extern const MetricsVersionSplit kMetricsVersionSplit;
bool MeasuredByTodaysMetrics(std::string_view stored, const Job& job, std::string_view core_now,
                             std::string_view sparkles_now, const MetricsVersionSplit& split = kMetricsVersionSplit);
// A stored row of `job` (its JobSources::ToJson, null for a row from before
// per-kernel ids) that today's code would give the same numbers under
// another id: its sources differ from `now` in the metrics version only,
// and MeasuredByTodaysMetrics holds.
bool Rekeyable(const Job& job, const nlohmann::json& stored_sources, const JobSources& now);

// The sources of `job` as this shimmer would run it, kept per process. An
// external sequence has none (its frames' content hashes are in the job).
Result<JobSources> SourcesOf(const Job& job);
// Forgets the kept sources: for a process that edits shaders (test hooks),
// scene files or normal maps in place and asks again.
void ForgetSources();

// The canonical JSON of the job as it describes itself: its fields with
// every parameter the variant reads resolved (defaults included, so that a
// default spelled out in a spec is the same job), without the file path of a
// user variant. Two jobs with one description are one job of a spec.
std::string JobDescription(const Job& job);

// 16 hex digits, stable across runs and machines. A row's id hashes the
// description, the test render's fingerprint, the reference id and the
// metrics version; FramesIdFrom, the frames alone (description and test
// fingerprint); ReferenceIdFrom, the reference's description (shot, size,
// motion, reference options) and its fingerprint. So a comment edit in a
// shader moves nothing, an edit of one variant moves that variant's ids, and
// a change of the metrics code moves rows but not frames. An external
// sequence's ids hash its frames' content.
std::string JobIdFrom(const Job& job, const JobSources& sources);
std::string FramesIdFrom(const Job& job, const JobSources& sources);
std::string ReferenceIdFrom(const Job& job, const JobSources& sources);

// The same with SourcesOf(job). A job that does not resolve (it fails when
// run, with the reason) gets an id of its description alone.
std::string JobId(const Job& job);
std::string FramesId(const Job& job);
std::string ReferenceId(const Job& job);

// Why the job with sources `now` is not the stored job with sources
// `before` (the same description): "kernel of `tk19` changed", "scene or
// camera content changed", "reference changed", "metrics version changed".
std::vector<std::string> WhyRerun(const Job& job, const JobSources& before, const JobSources& now);

// Jobs with index % n == i (i in [0, n)). Parses "i/n"; returns false on bad input.
bool ParseShard(const std::string& text, int* index, int* count);
std::vector<Job> ShardOf(const std::vector<Job>& jobs, int index, int count);

using shimmer::Fnv1a64Hex;  // job ids are FNV-1a hashes of canonical JSON

}  // namespace shimmer::experiments
