#include <gtest/gtest.h>

#include <filesystem>

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

#include "shimmer/experiments/job.h"
#include "shimmer/experiments/minimize.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::experiments {
namespace {

const char* kSpec = R"({
  "name": "t",
  "scenes": ["sphere", "sphere-field"],
  "materials": ["ggx:0.02", "beckmann:0.1"],
  "cameras": ["orbit"],
  "variants": [
    "none",
    {"name": "k16-beckmann-rect", "params": {"fp_max": [0.25, 1.0]}},
    {"name": "tk19", "params": {"kappa": {"from": 0.01, "to": 1, "steps": 3, "scale": "log"},
                                "sigma2": [0.1, 0.25]}},
    "supersample-2"
  ],
  "derivatives": ["quad", "analytic"],
  "size": [64, 32],
  "frames": 8,
  "reference": {"spp": 4}
})";

TEST(Spec, ParsesAndExpandsTheCrossProduct) {
  auto r = ParseSpec(kSpec, "t.json");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->width, 64);
  EXPECT_EQ(r->height, 32);
  const auto& kappa = r->variants[2].params.at("kappa");
  ASSERT_EQ(kappa.size(), 3u);
  EXPECT_NEAR(kappa[1], 0.1, 1e-12);  // log range: geometric midpoint
  // 2 scenes x 2 materials x 1 camera x ((2 + 3*2) variant points x 2 derivative sources + none + supersample-2,
  // which never read derivatives)
  const auto jobs = ExpandJobs(r.value());
  EXPECT_EQ(jobs.size(), 2u * 2 * 1 * (8 * 2 + 2));
  for (const Job& j : jobs)
    if (!ReadsDerivatives(j.variant)) {
      EXPECT_EQ(j.derivatives, "quad");
    }
  std::set<std::string> ids;
  for (const Job& j : jobs) ids.insert(JobId(j));
  EXPECT_EQ(ids.size(), jobs.size()) << "every job has its own id";
}

// Ids name stored results across runs, machines and versions of shimmer: the
// id of a fixed job with fixed sources is pinned here, so that a change to
// the canonical JSON, the parameter resolution or the hash shows up as this
// failure (and then means: every store's rows are recomputed). The sources
// themselves are pinned by what the kernel and content tests change.
TEST(Spec, IdsAreStable) {
  // FNV-1a 64, the published test vectors.
  EXPECT_EQ(Fnv1a64Hex(""), "cbf29ce484222325");
  EXPECT_EQ(Fnv1a64Hex("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(Fnv1a64Hex("foobar"), "85944171f73967e8");
  Job j;
  j.scene = "sphere-field";
  j.material = "ggx:0.02";
  j.camera = "orbit";
  j.variant = "k16-beckmann-rect";
  j.params = {{"fp_max", 0.5}};
  j.derivatives = "quad";
  j.width = j.height = 128;
  j.frames = 32;
  j.fps = 30;
  j.reference.spp = 8;
  j.reference.tolerance = 0;
  JobSources sources;
  sources.test = {"kernel-a", "inputs-a"};
  sources.reference = {"kernel-r", "inputs-r"};
  sources.metrics = "metrics-1";
  EXPECT_EQ(JobIdFrom(j, sources), "b142036ef03cd997");
  // A default spelled out is the same job; another value is not.
  Job spelled = j;
  spelled.params = {};
  Job defaulted = spelled;
  defaulted.params = {{"fp_max", 1.0}};
  EXPECT_EQ(JobIdFrom(spelled, sources), JobIdFrom(defaulted, sources));
  EXPECT_NE(JobIdFrom(spelled, sources), JobIdFrom(j, sources));
  // Each source moves the row; the frames move with the test render only;
  // the reference with its own render only.
  for (auto edit : {+[](JobSources& s) { s.test.kernel = "kernel-b"; }, +[](JobSources& s) { s.test.inputs = "b"; },
                    +[](JobSources& s) { s.reference.kernel = "b"; }, +[](JobSources& s) { s.metrics = "metrics-2"; }}) {
    JobSources other = sources;
    edit(other);
    EXPECT_NE(JobIdFrom(j, other), JobIdFrom(j, sources));
    const bool test_moved = other.test.kernel != sources.test.kernel || other.test.inputs != sources.test.inputs;
    EXPECT_EQ(FramesIdFrom(j, other) != FramesIdFrom(j, sources), test_moved);
    EXPECT_EQ(ReferenceIdFrom(j, other) != ReferenceIdFrom(j, sources), other.reference.kernel != "kernel-r");
  }
  // What WhyRerun says for each.
  JobSources other = sources;
  other.test.kernel = "kernel-b", other.metrics = "metrics-2";
  EXPECT_EQ(WhyRerun(j, sources, other),
            (std::vector<std::string>{"kernel of `k16-beckmann-rect` changed", "metrics version changed"}));
  EXPECT_TRUE(WhyRerun(j, sources, sources).empty());
  // Through JSON, as the store keeps them.
  const JobSources back = JobSources::FromJson(sources.ToJson());
  EXPECT_EQ(JobIdFrom(j, back), JobIdFrom(j, sources));
}

TEST(Spec, ReferencesAreShared) {
  const auto jobs = ExpandJobs(ParseSpec(kSpec, "t.json").value());
  // Same scene, material, camera: one reference for every variant and derivative source.
  std::set<std::string> refs;
  for (const Job& j : jobs) refs.insert(ReferenceId(j));
  EXPECT_EQ(refs.size(), 2u * 2 * 1);
  const Job& rect =
      *std::find_if(jobs.begin(), jobs.end(), [](const Job& j) { return j.variant == "k16-beckmann-rect"; });
  Job changed = rect;
  changed.params["fp_max"] = 0.5;
  EXPECT_NE(JobId(changed), JobId(rect));
  EXPECT_EQ(ReferenceId(changed), ReferenceId(rect));
  EXPECT_EQ(Job::FromJson(jobs[5].ToJson()).ToJson(), jobs[5].ToJson());
}

TEST(Spec, ShardsPartitionTheJobs) {
  const auto jobs = ExpandJobs(ParseSpec(kSpec, "t.json").value());
  std::multiset<std::string> seen;
  for (int i = 0; i < 3; ++i)
    for (const Job& j : ShardOf(jobs, i, 3)) seen.insert(JobId(j));
  EXPECT_EQ(seen.size(), jobs.size());
  for (const Job& j : jobs) EXPECT_EQ(seen.count(JobId(j)), 1u);
  int i = 0, n = 0;
  EXPECT_TRUE(ParseShard("2/5", &i, &n));
  EXPECT_EQ(i, 2);
  EXPECT_EQ(n, 5);
  EXPECT_FALSE(ParseShard("5/5", &i, &n));
  EXPECT_FALSE(ParseShard("1/0", &i, &n));
  EXPECT_FALSE(ParseShard("a/b", &i, &n));
  EXPECT_FALSE(ParseShard("1/2x", &i, &n));
}

std::string ErrorOf(std::string text) { return ParseSpec(text, "bad.json").error(); }

TEST(Spec, MalformedSpecsNameTheKeyAndLine) {
  const std::string base_head =
      "{\n  \"name\": \"b\",\n  \"scenes\": [\"sphere\"],\n  \"materials\": [\"ggx:0.1\"],\n"
      "  \"cameras\": [\"orbit\"],\n";
  std::string e = ErrorOf(base_head + "  \"variants\": [\"none\"],\n  \"frmes\": 8\n}");
  EXPECT_NE(e.find("bad.json:7"), std::string::npos) << e;
  EXPECT_NE(e.find("frmes: unknown key"), std::string::npos) << e;

  e = ErrorOf(base_head + "  \"variants\": [\"k16-nope\"]\n}");
  EXPECT_NE(e.find("bad.json:6: k16-nope: unknown variant"), std::string::npos) << e;

  e = ErrorOf(base_head + "  \"variants\": [{\"name\": \"tk19\", \"params\": {\"fp_max\": [1]}}]\n}");
  EXPECT_NE(e.find("fp_max"), std::string::npos) << e;
  EXPECT_NE(e.find("has no parameter"), std::string::npos) << e;

  e = ErrorOf(base_head + "  \"variants\": [\"none\"],\n  \"frames\": \"eight\"\n}");
  EXPECT_NE(e.find("frames: must be an integer in 1..4096, found \"eight\""), std::string::npos) << e;

  e = ErrorOf(
      "{\n  \"name\": \"b\",\n  \"scenes\": [],\n  \"materials\": [\"ggx:0.1\"],\n  \"cameras\": [\"orbit\"],\n"
      "  \"variants\": [\"none\"]\n}");
  EXPECT_NE(e.find("bad.json:3: scenes: is empty"), std::string::npos) << e;

  e = ErrorOf(base_head + "  \"variants\": [\"none\"],\n  \"size\": [64, 64\n}");
  EXPECT_NE(e.find("bad.json:8:1: not valid JSON"), std::string::npos) << e;

  e = ErrorOf(base_head +
              "  \"variants\": [{\"name\": \"tk19\", \"params\": {\"kappa\": {\"from\": 0, \"to\": 1, "
              "\"steps\": 3, \"scale\": \"log\"}}}]\n}");
  EXPECT_NE(e.find("log range needs from > 0"), std::string::npos) << e;

  e = ErrorOf(base_head + "  \"variants\": [\"none\"],\n  \"derivatives\": [\"sobel\"]\n}");
  EXPECT_NE(e.find("derivatives: must be quad"), std::string::npos) << e;

  e = ErrorOf(
      "{\"name\": \"b\", \"scenes\": [\"nowhere.json\"], \"materials\": [\"ggx:0.1\"], "
      "\"cameras\": [\"orbit\"], \"variants\": [\"none\"]}");
  EXPECT_NE(e.find("nowhere.json"), std::string::npos) << e;

  e = ErrorOf(
      "{\"name\": \"b\", \"scenes\": [\"sphere\"], \"materials\": [\"ggx:-1\"], "
      "\"cameras\": [\"orbit\"], \"variants\": [\"none\"]}");
  EXPECT_NE(e.find("ggx:-1"), std::string::npos) << e;

  e = ErrorOf(
      "{\"name\": \"b\", \"scenes\": [\"sphere\"], \"materials\": [\"ggx:0.1\"], "
      "\"cameras\": [\"spin\"], \"variants\": [\"none\"]}");
  EXPECT_NE(e.find("spin: unknown camera path"), std::string::npos) << e;
}

std::string FitSpec(const std::string& materials, const std::string& fit) {
  return "{\n  \"name\": \"f\",\n  \"scenes\": [\"sphere\"],\n  \"materials\": " + materials +
         ",\n  \"cameras\": [\"orbit\"],\n  \"variants\": [\"none\"],\n  \"fit\": " + fit + "\n}";
}
const std::string kShots = R"("train": {"scenes": ["sphere"], "cameras": ["orbit"]},
  "validate": {"scenes": ["wires"], "cameras": ["dolly"]})";

TEST(Spec, FitSectionParses) {
  auto r = ParseSpec(FitSpec(R"(["ggx:0.02", "beckmann:0.1"])",
                             R"([{"variants": ["k16-beckmann-rect"], "param": "fp_max", "bounds": [0.05, 2],
  "sweep_points": 5, "weights": {"bias": 4}, )" +
                                 kShots + R"(},
  {"variants": ["tk19"], "param": "kappa", )" +
                                 kShots + "}]"),
                     "f.json");
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->fits.size(), 2u);
  const FitConfig& c = r->fits[0];
  EXPECT_EQ(c.param, "fp_max");
  EXPECT_DOUBLE_EQ(c.lo, 0.05);
  EXPECT_DOUBLE_EQ(c.hi, 2);
  EXPECT_EQ(c.sweep_points, 5);
  EXPECT_DOUBLE_EQ(c.weights.bias, 4);
  EXPECT_DOUBLE_EQ(c.weights.flicker, 1);
  EXPECT_EQ(c.validate.scenes, std::vector<std::string>{"wires"});
  EXPECT_EQ((std::vector<double>{1.0, 0.7}), c.defaults);
  EXPECT_EQ(r->fits[1].param, "kappa");
}

TEST(Spec, BadFitConfigurationsAreRejectedUpFront) {
  auto error = [](const std::string& materials, const std::string& fit) {
    return ParseSpec(FitSpec(materials, fit), "f.json").error();
  };
  const std::string ggx = R"(["ggx:0.02"])";
  std::string e =
      error(ggx, R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "bounds": [2, 2], )" + kShots + "}");
  EXPECT_NE(e.find("bounds: are empty"), std::string::npos) << e;
  e = error(ggx, R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "bounds": [0, 1], )" + kShots + "}");
  EXPECT_NE(e.find("bounds: are empty or not positive"), std::string::npos) << e;
  e = error(ggx, R"({"variants": ["k16-beckmann-rect"], "param": "fp_mux", )" + kShots + "}");
  EXPECT_NE(e.find("k16-beckmann-rect: has no parameter \"fp_mux\" to fit (its parameters: fp_max)"), std::string::npos)
      << e;
  e = error(ggx, R"({"variants": ["tk19"], "param": "fp_max", )" + kShots + "}");
  EXPECT_NE(e.find("tk19: has no parameter \"fp_max\""), std::string::npos) << e;
  e = error(ggx, R"({"variants": ["toksvig-quad"], "param": "fp_max", )" + kShots + "}");
  EXPECT_NE(e.find("(its parameters: none)"), std::string::npos) << e;
  e = error(R"(["beckmann:0.1"])", R"({"variants": ["k16-ggx-rect-stable"], "param": "fp_max", )" + kShots + "}");
  EXPECT_NE(e.find("variant k16-ggx-rect-stable filters GGX only; use a ggx material (the spec lists beckmann:0.1)"),
            std::string::npos)
      << e;
  e = error(
      ggx,
      R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "train": {"scenes": ["sphere"], "cameras": ["orbit"]}})");
  EXPECT_NE(e.find("needs \"validate\""), std::string::npos) << e;
  e = error(
      ggx,
      R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "weights": {"flicker": 0, "spatial": 0, "bias": 0}, )" +
          kShots + "}");
  EXPECT_NE(e.find("weights: must be non-negative and not all zero"), std::string::npos) << e;
  e = error(
      ggx,
      R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "validate": {"scenes": ["sphere"], "cameras": ["spin"]}, "train": {"scenes": ["sphere"], "cameras": ["orbit"]}})");
  EXPECT_NE(e.find("spin: unknown camera path"), std::string::npos) << e;
  // A fit per normal map needs every shot's scene to have a map to replace.
  const std::string nm_shots = R"("train": {"scenes": ["nm-plane"], "cameras": ["orbit"]},
  "validate": {"scenes": ["sphere"], "cameras": ["dolly"]})";
  e = error(ggx, R"({"variants": ["lean"], "param": "nm_scale", "maps": ["bumps"], )" + nm_shots + "}");
  EXPECT_NE(e.find("maps: scene 'sphere@bumps': 'sphere' has no normal map"), std::string::npos) << e;
  e = error(ggx, R"({"variants": ["lean"], "param": "nm_scale", "maps": ["bumbs"], )" + kShots + "}");
  EXPECT_NE(e.find("maps: "), std::string::npos) << e;
}

// The specs the guide runs: each parses, and the ones with fits have them.
// They are run from the repository's root (scene files are named relative to
// the current directory: experiments/scenes/...), so they are read from there.
TEST(Spec, CommittedSpecsParse) {
  const std::filesystem::path was = std::filesystem::current_path();
  std::filesystem::current_path(SHIMMER_SOURCE_DIR);
  struct Back {
    std::filesystem::path to;
    ~Back() { std::filesystem::current_path(to); }
  } back{was};
  int specs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(SHIMMER_SOURCE_DIR) /
                                                                 "experiments/specs")) {
    if (entry.path().extension() != ".json") continue;
    // external.json reads frames the guide renders first (section 4c).
    if (entry.path().stem() == "external" &&
        !std::filesystem::exists(std::filesystem::path(SHIMMER_SOURCE_DIR) / "runs/external-frames/tk19"))
      continue;
    auto spec = LoadSpec(entry.path().string());
    EXPECT_TRUE(spec.ok()) << spec.error();
    ++specs;
    const std::string name = entry.path().stem().string();
    if (spec.ok() && (name == "standard" || name == "normal-maps" || name == "engine-settings")) {
      EXPECT_FALSE(spec->fits.empty()) << name;
    }
  }
  EXPECT_GE(specs, 5);
}

TEST(Spec, AJointFitParsesAndItsMistakesAreNamed) {
  const std::string shots = R"("train": {"scenes": ["sphere", "wires"], "cameras": ["orbit"]},
  "validate": {"scenes": ["sphere"], "cameras": ["dolly"]})";
  auto r = ParseSpec(FitSpec(R"(["ggx:0.05"])", R"({"variants": ["vlachos15"],
  "params": ["curvature_scale", "curvature_bias", "curvature_exponent"],
  "bounds": [[0.25, 8], [-0.5, 0.5], [0.1, 1]], "cross_validate": true, )" + shots + "}"),
                     "f.json");
  ASSERT_TRUE(r.ok()) << r.error();
  const FitConfig& c = r->fits[0];
  ASSERT_TRUE(c.IsJoint());
  EXPECT_EQ(c.joint_params.size(), 3u);
  EXPECT_FALSE(c.joint_bounds[1].Logarithmic());
  EXPECT_TRUE(c.joint_bounds[2].Logarithmic());
  EXPECT_EQ(c.sweep_points, 3);
  EXPECT_TRUE(c.cross_validate);
  auto error = [&](const std::string& fit) { return ParseSpec(FitSpec(R"(["ggx:0.05"])", fit), "f.json").error(); };
  const std::pair<std::string, std::string> bad[] = {
      {R"({"variants": ["filament"], "params": ["sigma2"], "bounds": [[0.01, 1]], )" + shots + "}",
       "params: a joint fit needs at least two parameters"},
      {R"({"variants": ["filament"], "params": ["sigma2", "kappa"], "bounds": [[0.01, 1]], )" + shots + "}",
       "bounds: must be one [lo, hi] per parameter (2)"},
      {R"({"variants": ["filament"], "params": ["sigma2", "kappa"], "bounds": [[0.01, 1], [0.3, 0.2]], )" + shots +
           "}",
       "bounds[1]: is empty"},
      {R"({"variants": ["tk19"], "params": ["sigma2", "fp_max"], "bounds": [[0.01, 1], [0.1, 2]], )" + shots + "}",
       "tk19: has no parameter \"fp_max\""},
      {R"({"variants": ["filament"], "params": ["sigma2", "sigma2"], "bounds": [[0.01, 1], [0.01, 1]], )" + shots +
           "}",
       "sigma2 is named twice"},
      {R"({"variants": ["filament"], "param": "kappa", "params": ["sigma2", "kappa"], "bounds": [[0.01, 1], [0.01, 1]], )" +
           shots + "}",
       "has both \"param\" and \"params\""},
      {R"({"variants": ["filament"], "params": ["sigma2", "kappa"], "bounds": [[0.01, 1], [0.01, 1]], "defaults": [[0.1, 0.1]], )" +
           shots + "}",
       "defaults: a joint fit compares with each variant's own defaults"},
      {R"({"variants": ["vlachos15"], "params": ["curvature_scale", "curvature_bias"], "bounds": [[0.1, 4], [-2, 0.5]], )" +
           shots + "}",
       "vlachos15: "},
      {R"({"variants": ["filament"], "params": ["sigma2", "kappa"], "bounds": [[0.01, 1], [0.01, 1]], "cross_validate": true,
  "train": {"scenes": ["sphere"], "cameras": ["orbit"]}, "validate": {"scenes": ["sphere"], "cameras": ["dolly"]}})",
       "cross_validate: leaves one training scene out: it needs at least two"},
      {R"({"variants": ["k16-beckmann-rect"], "param": "fp_max", "cross_validate": true, )" + shots + "}",
       "cross_validate: is for joint fits"},
  };
  for (const auto& [fit, message] : bad) {
    const std::string e = error(fit);
    EXPECT_NE(e.find(message), std::string::npos) << fit << "\n" << e;
  }
}

TEST(Spec, AFitPerNormalMapParses) {
  auto r = ParseSpec(FitSpec(R"(["ggx:0.05"])", R"({"variants": ["lean"], "param": "nm_scale",
  "maps": ["bumps", "ridges"], "train": {"scenes": ["nm-plane"], "cameras": ["orbit"]},
  "validate": {"scenes": ["nm-sphere"], "cameras": ["dolly"]}})"),
                     "f.json");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->fits[0].maps, (std::vector<std::string>{"bumps", "ridges"}));
  EXPECT_EQ(MappedScene("nm-plane", "ridges"), "nm-plane@ridges");
  EXPECT_EQ(MappedScene("nm-plane", ""), "nm-plane");
}

}  // namespace
}  // namespace shimmer::experiments

namespace shimmer::experiments {
namespace {
TEST(Spec, IdCoversDefaultParameters) {
  Job a;
  a.variant = "tk19";
  Job b = a;
  b.params["kappa"] = 0.18;  // the default, spelled out: same job
  EXPECT_EQ(JobId(a), JobId(b));
  b.params["kappa"] = 0.2;
  EXPECT_NE(JobId(a), JobId(b));
}
}  // namespace
}  // namespace shimmer::experiments

namespace shimmer::experiments {
namespace {

std::string TrustSpec(const std::string& tail) {
  return "{\n  \"name\": \"v\",\n  \"scenes\": [\"sphere\", \"wires\"],\n  \"materials\": [\"ggx:0.1\"],\n"
         "  \"cameras\": [\"orbit\"],\n  \"variants\": [\"none\", \"tk19\", \"supersample-2\"],\n"
         "  \"derivatives\": [\"quad\", \"analytic\"]" +
         tail + "\n}";
}

TEST(Spec, ReferenceReplicatesConvergenceAndBenchmarkParse) {
  auto r = ParseSpec(TrustSpec(R"(,
  "reference": {"spp": 6, "replicates": 8, "converge": {"energy": 0.01, "tv": 0.2, "frame_stride": 4}},
  "benchmark": {"size": [256, 128], "repetitions": 3, "precision": 0.05, "max_repetitions": 30})"),
                     "v.json");
  ASSERT_TRUE(r) << r.error();
  EXPECT_EQ(r->reference.replicates, 8);
  EXPECT_DOUBLE_EQ(r->reference.converge.energy, 0.01);
  EXPECT_DOUBLE_EQ(r->reference.converge.tv, 0.2);
  EXPECT_EQ(r->reference.converge.frame_stride, 4);
  EXPECT_TRUE(r->benchmark.enabled);
  EXPECT_EQ(r->benchmark.width, 256);
  EXPECT_EQ(r->benchmark.height, 128);
  EXPECT_EQ(r->benchmark.repetitions, 3);
  EXPECT_DOUBLE_EQ(r->benchmark.precision, 0.05);
  EXPECT_EQ(r->benchmark.max_repetitions, 30);
  // Defaults: 4 replicates, 2 % energy and 10 % tv, 512x512 in rounds of 5
  // until ±3 %, at most 60.
  auto d = ParseSpec(TrustSpec(""), "v.json");
  ASSERT_TRUE(d) << d.error();
  EXPECT_EQ(d->reference.replicates, 4);
  EXPECT_DOUBLE_EQ(d->reference.converge.energy, 0.02);
  EXPECT_DOUBLE_EQ(d->reference.converge.tv, 0.10);
  EXPECT_EQ(d->reference.converge.frame_stride, 1);
  EXPECT_EQ(d->benchmark.width, 512);
  EXPECT_EQ(d->benchmark.repetitions, 5);
  EXPECT_DOUBLE_EQ(d->benchmark.precision, 0.03);
  EXPECT_EQ(d->benchmark.max_repetitions, 300);
  auto off = ParseSpec(TrustSpec(",\n  \"benchmark\": false"), "v.json");
  ASSERT_TRUE(off) << off.error();
  EXPECT_FALSE(off->benchmark.enabled);

  // Replicates change the numbers, hence the ids; convergence tolerances change only verdicts.
  const Job a = ExpandJobs(*r).front(), b = ExpandJobs(*d).front();
  Job c = b;
  c.reference.replicates = 8;
  EXPECT_NE(ReferenceId(b), ReferenceId(c));
  EXPECT_NE(JobId(b), JobId(c));
  Job e = b;
  e.reference.converge.tv = 0.5;
  e.reference.converge.frame_stride = 3;
  EXPECT_EQ(JobId(b), JobId(e));
  EXPECT_EQ(ReferenceId(b), ReferenceId(e));
  EXPECT_EQ(Job::FromJson(a.ToJson()).reference.replicates, 8);

  for (const auto& [tail, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"(, "reference": {"replicates": 1})", "replicates: must be at least 2"},
           {R"(, "reference": {"converge": {"energy": 0}})", "converge: tolerances must be > 0"},
           {R"(, "reference": {"converge": {"enrgy": 0.1}})", "enrgy: unknown key"},
           {R"(, "reference": {"converge": {"frame_stride": 0}})", "converge.frame_stride: must be an integer"},
           {R"(, "benchmark": {"size": [511, 512]})", "benchmark.size: width and height must be even"},
           {R"(, "benchmark": {"repetitions": 0})", "benchmark.repetitions: must be an integer"},
           {R"(, "benchmark": 3)", "benchmark: must be true, false or"},
           {R"(, "benchmark": {"precision": 0})", "benchmark.precision: must be in (0, 1)"},
           {R"(, "benchmark": {"repetitions": 8, "max_repetitions": 4})", "max_repetitions: must be at least"},
       }) {
    auto bad = ParseSpec(TrustSpec(tail), "bad.json");
    ASSERT_FALSE(bad) << tail;
    EXPECT_NE(bad.error().find(expected), std::string::npos) << bad.error();
  }
}

TEST(Spec, ReferenceSppByMaterialGivesSharpMaterialsTheirOwnSampleCount) {
  const std::string two_materials = R"({"name": "v", "scenes": ["sphere"], "materials": ["ggx:0.01", "ggx:0.2"],
  "cameras": ["orbit"], "variants": ["none"],
  "reference": {"spp": 6, "spp_by_material": {"ggx:0.01": 12}}})";
  auto r = ParseSpec(two_materials, "m.json");
  ASSERT_TRUE(r) << r.error();
  const std::vector<Job> jobs = ExpandJobs(*r);
  ASSERT_EQ(jobs.size(), 2u);
  for (const Job& j : jobs) EXPECT_EQ(j.reference.spp, j.material == "ggx:0.01" ? 12 : 6) << j.material;

  for (const auto& [tail, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"(, "reference": {"spp_by_material": {"ggx:0.3": 12}})", "ggx:0.3: not one of the spec's materials"},
           {R"(, "reference": {"spp_by_material": {"ggx:0.1": 0}})", "spp_by_material: must be an integer"},
           {R"(, "reference": {"spp_by_material": [12]})", "spp_by_material: must be {"},
       }) {
    auto bad = ParseSpec(TrustSpec(tail), "bad.json");
    ASSERT_FALSE(bad) << tail;
    EXPECT_NE(bad.error().find(expected), std::string::npos) << bad.error();
  }
}

// spp_by_scene gives a scene its own samples, before spp_by_material.
TEST(Spec, ReferenceSppBySceneComesBeforeTheMaterials) {
  const std::string spec = R"({"name": "v", "scenes": ["sphere", "wires"], "materials": ["ggx:0.01", "ggx:0.2"],
  "cameras": ["orbit"], "variants": ["none"],
  "reference": {"spp": 6, "spp_by_material": {"ggx:0.01": 12}, "spp_by_scene": {"wires": 3}}})";
  auto r = ParseSpec(spec, "m.json");
  ASSERT_TRUE(r) << r.error();
  const std::vector<Job> jobs = ExpandJobs(*r);
  ASSERT_EQ(jobs.size(), 4u);
  for (const Job& j : jobs)
    EXPECT_EQ(j.reference.spp, j.scene == "wires" ? 3 : (j.material == "ggx:0.01" ? 12 : 6)) << j.scene << " " << j.material;

  for (const auto& [tail, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"(, "reference": {"spp_by_scene": {"wirez": 4}})", "wirez: not one of the spec's scenes"},
           {R"(, "reference": {"spp_by_scene": {"sphere": 0}})", "spp_by_scene: must be an integer"},
           {R"(, "reference": {"spp_by_scene": [4]})", "spp_by_scene: must be {"},
       }) {
    auto bad = ParseSpec(TrustSpec(tail), "bad.json");
    ASSERT_FALSE(bad) << tail;
    EXPECT_NE(bad.error().find(expected), std::string::npos) << bad.error();
  }
}

TEST(Spec, SignedRankCriticalRanksMatchTheWilcoxonTable) {
  // Two-sided 5 % critical values of the signed-rank statistic (Wilcoxon's
  // table: T <= 0, 2, 8, 52 rejects at n = 6, 7, 10, 20), plus one.
  EXPECT_EQ(SignedRankCriticalRank(5), 0);  // no 95 % interval from 5 pairs: 2/32 > 5 %
  EXPECT_EQ(SignedRankCriticalRank(6), 1);
  EXPECT_EQ(SignedRankCriticalRank(7), 3);
  EXPECT_EQ(SignedRankCriticalRank(10), 9);
  EXPECT_EQ(SignedRankCriticalRank(20), 53);
  // The normal approximation takes over past 200 pairs without a jump.
  const double exact = SignedRankCriticalRank(200), approximate = SignedRankCriticalRank(201);
  EXPECT_GT(approximate, exact);
  EXPECT_LT(approximate / exact, 1.02);
}

TEST(Spec, PairedCostRatiosCarryASignedRankInterval) {
  // Exact ratios: no spread, a zero-width interval.
  RatioEstimate exact = PairedRatio({12, 24, 36, 48, 60, 72}, {10, 20, 30, 40, 50, 60});
  EXPECT_NEAR(exact.ratio, 1.2, 1e-12);
  EXPECT_NEAR(exact.lo, 1.2, 1e-12);
  EXPECT_NEAR(exact.hi, 1.2, 1e-12);
  EXPECT_TRUE(exact.Within(0.03));
  // Log ratios 0.1 .. 0.6: the Walsh averages' median is 0.35; with n = 6
  // the interval is their extremes, 0.1 and 0.6.
  std::vector<double> test;
  for (double d : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}) test.push_back(std::exp(d));
  RatioEstimate spread = PairedRatio(test, std::vector<double>(6, 1.0));
  EXPECT_EQ(spread.n, 6);
  EXPECT_NEAR(spread.ratio, std::exp(0.35), 1e-12);
  EXPECT_NEAR(spread.lo, std::exp(0.1), 1e-12);
  EXPECT_NEAR(spread.hi, std::exp(0.6), 1e-12);
  EXPECT_FALSE(spread.Within(0.03));
  // Pairing: a common drift (the machine slowing) cancels.
  RatioEstimate drift = PairedRatio({1.1, 2.2, 4.4, 8.8, 17.6, 35.2}, {1, 2, 4, 8, 16, 32});
  EXPECT_NEAR(drift.lo, 1.1, 1e-12);
  EXPECT_NEAR(drift.hi, 1.1, 1e-12);
  // Robust to a slow frame: 29 pairs within ±1 % of 1.1 and one pair whose
  // variant frame a slow spell tripled. The rank interval stays within
  // ±3 %; the mean of the logs with its t interval would not.
  std::vector<double> variant, none;
  for (int i = 0; i < 30; ++i) {
    none.push_back(100);
    variant.push_back(110 * (1 + 0.01 * std::sin(1.7 * i)));
  }
  variant[17] *= 3;
  RatioEstimate robust = PairedRatio(variant, none);
  EXPECT_NEAR(robust.ratio, 1.1, 0.01);
  EXPECT_TRUE(robust.Within(0.03)) << robust.lo << " " << robust.hi;
  double mean = 0, squares = 0;
  for (int i = 0; i < 30; ++i) mean += std::log(variant[i] / none[i]) / 30;
  for (int i = 0; i < 30; ++i) squares += std::pow(std::log(variant[i] / none[i]) - mean, 2);
  EXPECT_GT(StudentT975(29) * std::sqrt(squares / 29 / 30), std::log(1.03));
  // Fewer than 6 pairs: an estimate, no interval.
  RatioEstimate few = PairedRatio({2, 2, 2}, {1, 1, 1});
  EXPECT_DOUBLE_EQ(few.ratio, 2);
  EXPECT_EQ(few.hi, 0);
  EXPECT_FALSE(few.Within(0.5));
}

TEST(Spec, BenchmarkBatchesTimeEachJobOnceUnderItsOwnSourceWithNoneFirst) {
  auto r = ParseSpec(TrustSpec(""), "v.json");
  ASSERT_TRUE(r) << r.error();
  const auto batches = BenchmarkBatches(ExpandJobs(*r));
  // 2 scenes x 2 derivative sources. supersample-2 reads no derivatives: its
  // one job (under quad, the first source) is timed in the quad batch only,
  // where its row's cost is joined; every batch has its own `none` first.
  ASSERT_EQ(batches.size(), 4u);
  for (const BenchmarkBatch& b : batches) {
    std::vector<std::string> variants;
    for (const Job& j : b.jobs) {
      variants.push_back(j.variant);
      EXPECT_EQ(j.scene, b.scene);
      EXPECT_EQ(j.derivatives, b.derivatives);
    }
    const std::vector<std::string> expected =
        b.derivatives == "quad" ? std::vector<std::string>{"none", "tk19", "supersample-2"}
                                : std::vector<std::string>{"none", "tk19"};
    EXPECT_EQ(variants, expected) << b.scene << " " << b.derivatives;
  }
  // A scene whose jobs all use one source has no batch under the other.
  auto quad_only = ParseSpec(
      TrustSpec(R"(,
  "groups": [{"scenes": ["nm-plane"], "materials": ["ggx:0.05"], "derivatives": ["quad"],
              "variants": ["none", "nm-mip"]}])"),
      "v.json");
  ASSERT_TRUE(quad_only) << quad_only.error();
  int nm_batches = 0;
  for (const BenchmarkBatch& b : BenchmarkBatches(ExpandJobs(*quad_only)))
    if (b.scene == "nm-plane") {
      ++nm_batches;
      EXPECT_EQ(b.derivatives, "quad");
    }
  EXPECT_EQ(nm_batches, 1);
}

}  // namespace
}  // namespace shimmer::experiments

namespace shimmer::experiments {
namespace {

// Lines: 1 "{", 2 name, 3 scenes, 4 materials, 5 cameras, 6 variants, 7 "groups" (and what `groups` spans).
std::string GroupSpec(const std::string& groups, const std::string& tail = "") {
  return "{\n  \"name\": \"g\",\n  \"scenes\": [\"sphere\"],\n  \"materials\": [\"ggx:0.1\"],\n"
         "  \"cameras\": [\"orbit\"],\n  \"variants\": [\"none\", \"tk19\"],\n  \"groups\": " +
         groups + tail + "\n}";
}

std::string Describe(const Job& j) {
  std::string params;
  for (const auto& [name, value] : j.params) params += " " + name + "=" + std::to_string(value);
  return j.scene + " " + j.material + " " + j.camera + " " + j.variant + params + " " + j.derivatives;
}

std::vector<std::string> Described(const std::vector<Job>& jobs) {
  std::vector<std::string> out;
  for (const Job& j : jobs) out.push_back(Describe(j));
  return out;
}

TEST(Spec, GroupsAddTheirCrossProductsAfterTheTopLevelOnes) {
  auto r = ParseSpec(
      GroupSpec(R"([{"scenes": ["wires"], "variants": ["none", {"name": "tk19", "params": {"kappa": [0.1, 0.3]}}]}])"),
      "g.json");
  ASSERT_TRUE(r) << r.error();
  ASSERT_EQ(r->groups.size(), 1u);
  // The top-level fields stay the top level's.
  EXPECT_EQ(r->scenes, std::vector<std::string>{"sphere"});
  EXPECT_EQ(r->variants.size(), 2u);
  const std::vector<ShotGroup> all = AllGroups(*r);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].scenes, std::vector<std::string>{"sphere"});
  EXPECT_EQ(all[1].scenes, std::vector<std::string>{"wires"});
  EXPECT_EQ(all[1].variants[1].params.at("kappa"), (std::vector<double>{0.1, 0.3}));
  EXPECT_EQ(Described(ExpandJobs(*r)), (std::vector<std::string>{
                                           "sphere ggx:0.1 orbit none quad",
                                           "sphere ggx:0.1 orbit tk19 quad",
                                           "wires ggx:0.1 orbit none quad",
                                           "wires ggx:0.1 orbit tk19 kappa=0.100000 quad",
                                           "wires ggx:0.1 orbit tk19 kappa=0.300000 quad",
                                       }));
}

TEST(Spec, AGroupInheritsTheKeysItOmits) {
  auto r = ParseSpec(GroupSpec(R"([{"materials": ["beckmann:0.1"]}])", R"(,
  "derivatives": ["quad", "analytic"])"),
                     "g.json");
  ASSERT_TRUE(r) << r.error();
  ASSERT_EQ(r->groups.size(), 1u);
  const ShotGroup& g = r->groups[0];
  EXPECT_EQ(g.materials, std::vector<std::string>{"beckmann:0.1"});
  EXPECT_EQ(g.scenes, r->scenes);
  EXPECT_EQ(g.cameras, r->cameras);
  EXPECT_EQ(g.derivatives, (std::vector<std::string>{"quad", "analytic"}));
  ASSERT_EQ(g.variants.size(), 2u);
  EXPECT_EQ(g.variants[0].name, "none");
  EXPECT_EQ(g.variants[1].name, "tk19");
  // Each of the two materials: none once, tk19 under both sources.
  EXPECT_EQ(Described(ExpandJobs(*r)), (std::vector<std::string>{
                                           "sphere ggx:0.1 orbit none quad",
                                           "sphere ggx:0.1 orbit tk19 quad",
                                           "sphere ggx:0.1 orbit tk19 analytic",
                                           "sphere beckmann:0.1 orbit none quad",
                                           "sphere beckmann:0.1 orbit tk19 quad",
                                           "sphere beckmann:0.1 orbit tk19 analytic",
                                       }));
}

TEST(Spec, AJobOfTwoGroupsIsRunOnce) {
  // The first group repeats the top level's variants and adds one; the second
  // repeats the first; the third spells out tk19's default kappa (the same
  // job as "tk19"); the fourth adds a derivative source, which `none` never
  // reads.
  auto r = ParseSpec(GroupSpec(R"([
    {"variants": ["none", "tk19", "k16-beckmann-rect"]},
    {"variants": ["none", "tk19", "k16-beckmann-rect"]},
    {"variants": [{"name": "tk19", "params": {"kappa": [0.18]}}]},
    {"derivatives": ["analytic"]}
  ])"),
                     "g.json");
  ASSERT_TRUE(r) << r.error();
  ASSERT_EQ(r->groups.size(), 4u);
  const std::vector<Job> jobs = ExpandJobs(*r);
  EXPECT_EQ(Described(jobs), (std::vector<std::string>{
                                 "sphere ggx:0.1 orbit none quad",
                                 "sphere ggx:0.1 orbit tk19 quad",
                                 "sphere ggx:0.1 orbit k16-beckmann-rect quad",
                                 "sphere ggx:0.1 orbit tk19 analytic",
                             }));
  std::set<std::string> ids;
  for (const Job& j : jobs) ids.insert(JobId(j));
  EXPECT_EQ(ids.size(), jobs.size());
}

TEST(Spec, MalformedGroupsNameTheGroupAndItsKey) {
  for (const auto& [groups, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"([{"scenes": ["wires"]}, {"scenez": ["wires"]}])", "groups[1].scenez: unknown key (expected one of: "},
           {R"([{}])", "groups[0]: is empty: give at least one of"},
           {R"({"scenes": ["wires"]})", "groups: must be a non-empty list of objects"},
           {R"([])", "groups: must be a non-empty list of objects"},
           {R"(["wires"])", "groups[0]: must be an object with any of: cameras, derivatives"},
           {R"([{"scenes": ["wires"]}, {"variants": ["k16-nope"]}])", "groups[1].variants: k16-nope: unknown variant"},
           {R"([{"variants": [{"name": "tk19", "params": {"fp_max": [1]}}]}])",
            "groups[0].variants: fp_max: variant tk19 has no parameter"},
           {R"([{"variants": []}])", "groups[0].variants: must be a non-empty array"},
           {R"([{"scenes": ["nowhere.json"]}])", "groups[0].scenes: nowhere.json: "},
           {R"([{"scenes": []}])", "groups[0].scenes: is empty"},
           {R"([{"materials": ["ggx:-1"]}])", "groups[0].materials: ggx:-1: "},
           {R"([{"cameras": ["spin"]}])", "groups[0].cameras: spin: unknown camera path"},
           {R"([{"derivatives": ["sobel"]}])", "groups[0].derivatives: must be quad"},
       }) {
    auto bad = ParseSpec(GroupSpec(groups), "bad.json");
    ASSERT_FALSE(bad) << groups;
    EXPECT_NE(bad.error().find(expected), std::string::npos) << bad.error();
  }
  // The line is the group's, not that of the top level's key of the same name.
  std::string e = ErrorOf(GroupSpec("[\n    {\"scenes\": [\"wires\"]},\n    {\"variants\": \"none\"}\n  ]"));
  EXPECT_NE(e.find("bad.json:9: groups[1].variants: must be a non-empty array"), std::string::npos) << e;
  e = ErrorOf(GroupSpec("[\n    {\"scenes\": [\"wires\"]},\n    {}\n  ]"));
  EXPECT_NE(e.find("bad.json:9: groups[1]: is empty"), std::string::npos) << e;
  e = ErrorOf(GroupSpec("[\n    {\"scenes\": [\"wires\"]},\n    {\"scenes\": [\"wires\"], \"scenez\": 1}\n  ]"));
  EXPECT_NE(e.find("bad.json:9: groups[1].scenez: unknown key"), std::string::npos) << e;
}

TEST(Spec, SppByMaterialMayNameAMaterialOnlyAGroupHas) {
  auto r = ParseSpec(GroupSpec(R"([{"materials": ["ggx:0.01"]}])", R"(,
  "reference": {"spp": 6, "spp_by_material": {"ggx:0.01": 12}})"),
                     "g.json");
  ASSERT_TRUE(r) << r.error();
  for (const Job& j : ExpandJobs(*r)) EXPECT_EQ(j.reference.spp, j.material == "ggx:0.01" ? 12 : 6) << j.material;
  auto bad = ParseSpec(GroupSpec(R"([{"materials": ["ggx:0.01"]}])", R"(,
  "reference": {"spp_by_material": {"ggx:0.3": 12}})"),
                       "bad.json");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("spp_by_material: ggx:0.3: not one of the spec's materials"), std::string::npos)
      << bad.error();
}

TEST(Spec, AFitKeepsTheTopLevelMaterials) {
  // A GGX-only variant is fitted on the top level's GGX material; the
  // Beckmann material of a group is not fitted, so not refused.
  auto r = ParseSpec(GroupSpec(R"([{"materials": ["beckmann:0.1"]}])", R"(,
  "fit": {"variants": ["k16-ggx-rect-stable"], "param": "fp_max", )" + kShots +
                                                                           "}"),
                     "f.json");
  ASSERT_TRUE(r) << r.error();
  EXPECT_EQ(r->materials, std::vector<std::string>{"ggx:0.1"});
}

TEST(Spec, TheJobBoundCountsEveryGroup) {
  // 10000 x 6 points of tk19: 60000 jobs, within the bound alone; twice that with a group.
  const std::string head =
      "{\"name\": \"g\", \"scenes\": [\"sphere\"], \"materials\": [\"ggx:0.1\"], \"cameras\": [\"orbit\"], "
      "\"variants\": [{\"name\": \"tk19\", \"params\": {\"kappa\": {\"from\": 0.01, \"to\": 1, \"steps\": 10000}, "
      "\"sigma2\": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]}}]";
  ASSERT_TRUE(ParseSpec(head + "}", "g.json"));
  const std::string e = ErrorOf(head + ", \"groups\": [{\"scenes\": [\"wires\"]}]}");
  EXPECT_NE(e.find("groups: the spec expands to 120000 jobs (top level and groups together); at most 100000"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace shimmer::experiments
