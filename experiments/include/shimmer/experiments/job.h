// Jobs: one (scene, material, camera, variant with parameter values,
// derivative source) of a spec, with an id that hashes every resolved
// parameter and the shading core, so reruns skip finished work.
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

namespace shimmer::experiments {

struct Job {
  std::string scene;
  std::string material;
  std::string camera;
  std::string variant;
  std::map<std::string, double> params;  // only the values the spec sweeps; defaults are implied by the core version
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
// job (by JobId) that is there already is left out: the first one stays.
std::vector<Job> ExpandJobs(const Spec& spec);

// 16 hex digits: FNV-1a 64 of the canonical JSON of the job, every parameter
// value the variant reads (defaults included) and the shading core's version
// (external sequences: their frames' content, not the core, which renders
// none of their pixels). Stable across runs and machines.
std::string JobId(const Job& job);
// The same for a given shading-core version: ids can be pinned by tests
// without every GLSL edit changing the expected value.
std::string JobIdForCore(const Job& job, std::string_view core_version);

// The reference a job is measured against: shared by every variant and
// derivative source of the same scene, material, camera, size and motion; an
// external sequence's is the content of its reference frames.
std::string ReferenceId(const Job& job);

// Hash of the GLSL shading core text: changes whenever the filter math does.
std::string ShadingCoreVersion();
// The hash of `root` and every source it includes, transitively, in the
// order of `sources` (name then text of each); sources outside that closure
// do not count.
std::string CoreVersionOf(std::span<const std::pair<std::string_view, std::string_view>> sources,
                          std::string_view root);

// Jobs with index % n == i (i in [0, n)). Parses "i/n"; returns false on bad input.
bool ParseShard(const std::string& text, int* index, int* count);
std::vector<Job> ShardOf(const std::vector<Job>& jobs, int index, int count);

using shimmer::Fnv1a64Hex;  // job ids are FNV-1a hashes of canonical JSON

}  // namespace shimmer::experiments
