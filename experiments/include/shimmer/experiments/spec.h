// An experiment spec: the cross product of scenes x materials x cameras x
// variants (with parameter values) x derivative sources, plus one more such
// cross product per entry of "groups", at one resolution, frame count and
// reference quality. Parsed and validated before any work.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/experiments/minimize.h"
#include "shimmer/core/result.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::experiments {

struct VariantSweep {
  std::string name;
  // Parameter name -> values to take (a list, or a range expanded here).
  std::map<std::string, std::vector<double>> params;
};

// A user's variant file named in a spec (variant entry {"file", "name",
// "params"}), parsed: its file as resolved against the spec's folder, the
// hash of its content (job ids hash it, so an edited file is new work) and
// the parameters it declares (docs/variants.md).
using UserVariantRef = std::shared_ptr<const shading::UserVariant>;

// How much a shot's metrics of `none` may move when the reference doubles
// its samples per axis before the shot is called unconverged.
struct ConvergenceTolerance {
  double energy = 0.02;  // absolute change of energy_bias
  double tv = 0.10;      // relative change of tv_ref and of tv_err
  // The check measures frames 0, k, 2k, ... of the shot (its camera path at
  // 1/k of the frame rate): the reference at twice the samples per axis costs
  // four times the reference, and on every frame it was a third of a run.
  int frame_stride = 1;
};

struct ReferenceQuality {
  int spp = 8;                    // N x N stratified samples per pixel and replicate
  double tolerance = 0;           // > 0: adaptive to this relative standard error instead
  int replicates = 4;             // independent N x N patterns per pixel: the standard error comes from their spread
  ConvergenceTolerance converge;  // not part of job ids: it changes verdicts, not numbers
};

// Dedicated timing renders (spec key "benchmark"; false turns them off).
struct BenchmarkOptions {
  bool enabled = true;
  int width = 512, height = 512;
  int repetitions = 5;        // a round: repetitions are added a round at a time
  double precision = 0.03;    // ... until every ratio's 95 % interval is within ±precision
  int max_repetitions = 300;  // ... or this many were timed
};

struct MetricOptions {
  bool highlight_mask = true;
  // Reference specular luminance above which a pixel is a highlight. Lower
  // than `shimmer metrics`' default of 1: shimmer's scenes light at a few
  // units of irradiance, and a pixel-averaged highlight on a sub-pixel sphere
  // stays well below 1.
  double highlight_threshold = 0.1;
  int segment = 0;  // Welch segment length; 0: min(frames, 64)
  // Luminance above which a pixel is a sparkle (docs/metrics.md, "Sparkle
  // statistics"); 0: no sparkle statistics.
  double sparkle_threshold = 0;
};

struct FitWeights {
  double flicker = 1, spatial = 1, bias = 1;
};

// A set of shots (scene x camera) the objective averages over.
struct ShotSet {
  std::vector<std::string> scenes, cameras;
};

// One `fit` entry: for each of the spec's top-level materials (not those of
// its groups) and each variant, the value of `param` in [lo, hi] that
// minimises the objective on `train`, validated on `validate` against the
// published `defaults`. With `maps`, once per normal map as well: every shot's
// scene renders with that map in place of its own (scene "SCENE@MAP").
struct FitConfig {
  std::vector<std::string> variants;
  std::string param = "fp_max";
  double lo = 0.01, hi = 4;
  int sweep_points = 7;
  std::vector<double> defaults{1.0, 0.7};  // seed 000's fp_max = 1, seed 001's 0.7
  std::string derivatives = "quad";
  ShotSet train, validate;
  FitWeights weights;
  std::vector<std::string> maps;  // normal maps (built-in names or files); empty: each scene's own

  // A joint fit (spec key "params" instead of "param"): several parameters
  // of each variant at once, on a grid of `sweep_points` per axis and then
  // Ceres (MinimizeND). `param`, `lo`, `hi` and `defaults` are then unused.
  std::vector<std::string> joint_params;
  std::vector<FitAxis> joint_bounds;  // compared with each variant's own defaults (an engine's shipped settings)
  // Leave each training scene out in turn (fit on the others, measure on it),
  // and fit each training scene alone (measured on it under the validation
  // cameras): how far a setting transfers across geometry classes.
  bool cross_validate = false;
  bool IsJoint() const { return !joint_params.empty(); }
};

// "SCENE@MAP" (scene::LoadScene): `scene` with every normal map replaced by
// `map`; `scene` itself when `map` is empty.
std::string MappedScene(const std::string& scene, const std::string& map);

// One cross product of shots and variants: scenes x materials x cameras x
// variants (with parameter values) x derivative sources.
struct ShotGroup {
  std::vector<std::string> scenes;
  std::vector<std::string> materials;
  std::vector<std::string> cameras;
  std::vector<VariantSweep> variants;
  std::vector<std::string> derivatives;
};

// An engine's own frames (spec section "sequences"; docs/external.md):
// a test sequence and its reference, measured with the same metrics,
// intervals and region rules as the rendered jobs and reported beside them,
// marked external. Paths are resolved against the spec's folder; the hashes
// are of every frame's bytes, so re-rendered frames are new work.
struct ExternalFrames {
  std::string test, reference;
  std::string test_hash, reference_hash;
  double ms_per_frame = 0;  // the user's own cost; 0: not given
  std::string device;       // where that cost was measured
  bool operator==(const ExternalFrames&) const = default;
};

struct ExternalSequence {
  std::string label;  // the row's name in the report, like a variant's
  // The shot it shows: a shot the spec renders puts the sequence in that
  // shot's tables; any other names a table of its own.
  std::string scene = "external", material = "-", camera = "-";
  double fps = 0;  // used when the sequence has no sequence.json to say; 0: the spec's fps
  int width = 0, height = 0, frames = 0;
  ExternalFrames files;
};

// The hash of every frame of a sequence (a directory of EXR frames or a
// sequence.json): file names and bytes, in frame order. Where the frames
// lie does not count.
Result<std::string> SequenceContentHash(const std::string& path);
// `sequence` with its frames' size, count and hashes, after opening every
// frame's header of its test and reference sequences (files.test and
// files.reference) and checking that they match. On failure `bad_key` says
// which of "test" and "reference" is wrong.
Result<ExternalSequence> OpenExternalSequence(ExternalSequence sequence, std::string* bad_key);

struct Spec {
  std::string name;
  // The top-level cross product (the first of AllGroups).
  std::vector<std::string> scenes;
  std::vector<std::string> materials;
  std::vector<std::string> cameras;
  std::vector<VariantSweep> variants;
  std::vector<std::string> derivatives{"quad"};
  // Spec key "groups": more cross products, after the top-level one, each
  // resolved (a key a group omits holds the top-level value).
  std::vector<ShotGroup> groups;
  int width = 128, height = 128;
  int frames = 32;
  double fps = 30;
  ReferenceQuality reference;
  // reference.spp_by_material: N per material where the default N is not
  // enough (sharp highlights need more samples per axis than rough ones).
  std::map<std::string, int> reference_spp_by_material;
  // reference.spp_by_scene: N per scene, before spp_by_material (a mesh
  // scene's samples cost several times an analytic one's: docs/scenes.md).
  std::map<std::string, int> reference_spp_by_scene;
  MetricOptions metrics;
  BenchmarkOptions benchmark;
  std::vector<FitConfig> fits;  // the `fit` section: one object or a list
  // User variants by the name their entries give them (in any group).
  std::map<std::string, UserVariantRef> user_variants;
  // Spec key "sequences". A spec with sequences may leave out the rendered
  // cross product (scenes, materials, cameras, variants) altogether.
  std::vector<ExternalSequence> sequences;
};

// Loads `path`, checks that it compiles as a variant and registers it as
// `name` (a file's name must not be a built-in variant's, nor another
// file's). The error names the file, and its line where the file is wrong.
Result<UserVariantRef> AddUserVariant(Spec* spec, const std::string& path, const std::string& name);
// What a fit of `param` in [lo, hi] needs of `variant` (a catalogue name or
// one of spec.user_variants): that it has the parameter, the bounds lie in
// its range, and it shades every material of the spec. Empty when it does.
Status CheckFitVariant(const Spec& spec, const std::string& variant, const std::string& param, double lo, double hi);

// The top-level cross product, then each of spec.groups: every group of
// shots a spec's jobs come from (ExpandJobs).
std::vector<ShotGroup> AllGroups(const Spec& spec);

// Bounds on what a spec may ask for (each is named in the error).
inline constexpr int kMaxJobs = 100000;  // all groups together
inline constexpr int kMaxSweepPoints = 64;
inline constexpr int kMaxRangeSteps = 10000;
inline constexpr int kMaxSpecFrames = 4096;

// `source` names the text in messages (usually the file name); errors read
// "<source>:<line>: <key>: <problem>". Variant files are looked for relative
// to the folder of `source`.
Result<Spec> ParseSpec(std::string_view json_text, const std::string& source);
Result<Spec> LoadSpec(const std::string& path);

}  // namespace shimmer::experiments
