// Bad input to every subcommand of the built `shimmer` binary, one table row a
// case. Each case runs in a fresh directory and must end with
//  (a) the exit code it states: 2 for a bad option or a bad input file, 1 for a
//      runtime failure (a full disk, a store another process is using);
//  (b) exactly one stderr line that starts with "shimmer: error: ", containing
//      the case's substring (the file, key or flag that is wrong). Other stderr
//      lines (progress, "shimmer: warning: ...", the driver's banner) are fine
//      as long as none of them mentions an error, an exception or an abort:
//      the one error line is the only error a user sees. No line on stdout or
//      stderr may carry a raw library text (std::bad_alloc, stoi, nlohmann's
//      "[json.exception...").
//  (c) the directory exactly as it was: nothing new (no file under a final
//      name, no hidden ".*.partial-*" leftover, no created-but-empty
//      directory), nothing removed, nothing changed.
// A full disk is a file-size limit: the command runs as
// `sh -c 'ulimit -f N; exec shimmer ...'`; shimmer ignores SIGXFSZ, so its
// writes fail with EFBIG. Permission bits do not stop root, so the read-only
// directory cases are skipped when the test runs as root.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "shimmer/core/exr_output.h"
#include "shimmer/core/host_memory.h"

namespace {

namespace fs = std::filesystem;

// --- where the cases run --------------------------------------------------------

fs::path Root() {
  static const fs::path root = [] {
    setenv("XDG_RUNTIME_DIR", "/tmp", 0);
    fs::path r = fs::temp_directory_path() / ("shimmer-bad-input-" + std::to_string(::getpid()));
    fs::remove_all(r);
    fs::create_directories(r);
    return r;
  }();
  return root;
}

// Removes the root, with read-only directories made writable first.
class RootCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    if (!fs::exists(Root(), ec)) return;
    for (fs::recursive_directory_iterator it(Root(), ec), end; !ec && it != end; it.increment(ec))
      if (it->is_directory(ec)) fs::permissions(it->path(), fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(Root(), ec);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new RootCleanup);

std::string ReadAll(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteText(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("fixture text has no '" + from + "'");
  return text.replace(at, from.size(), to);
}

// --- fixtures -------------------------------------------------------------------

// Frames of R,G,B and specular.R/G/B; `noise` makes them incompressible (the
// maps of a full-disk case must outgrow the limit).
void WriteSequence(const fs::path& dir, int width, int height, int frames, bool noise = false) {
  fs::create_directories(dir);
  const std::size_t n = std::size_t(width) * height;
  std::uint32_t state = 12345;
  for (int t = 0; t < frames; ++t) {
    std::vector<float> beauty(n), specular(n);
    for (std::size_t i = 0; i < n; ++i) {
      state = state * 1664525u + 1013904223u;
      const float r = noise ? float(state >> 8) / float(1 << 24) : 0.0f;
      beauty[i] = 0.5f + 0.1f * float((i + t) % 3) + r;
      specular[i] = (i == n / 2 ? 4.0f : 0.2f) + 0.05f * float((i + 2 * t) % 5) + r;
    }
    std::vector<shimmer::ExrPlane> planes = {{"R", beauty.data()},
                                             {"G", beauty.data()},
                                             {"B", beauty.data()},
                                             {"specular.R", specular.data()},
                                             {"specular.G", specular.data()},
                                             {"specular.B", specular.data()}};
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.exr", t);
    const shimmer::Status s = shimmer::WriteExr(dir / name, width, height, planes);
    if (!s) throw std::runtime_error(s.error());
  }
}

// The header of an EXR written above claims a 100000 x 100000 data window
// (its 16 x 16 pixels unchanged): a reader that believes it allocates 40 GB a plane.
void ForgeDataWindow(const fs::path& file) {
  std::string bytes = ReadAll(file);
  for (const std::string attribute : {"dataWindow", "displayWindow"}) {
    const std::string name = attribute + std::string("\0box2i\0", 7);
    const auto at = bytes.find(name);
    if (at == std::string::npos) throw std::logic_error(file.string() + " has no " + attribute);
    const std::int32_t box[4] = {0, 0, 99999, 99999};  // little-endian, as EXR is
    bytes.replace(at + name.size() + 4, sizeof box, reinterpret_cast<const char*>(box), sizeof box);
  }
  std::ofstream(file, std::ios::binary) << bytes;
}

const char* const kSpec = R"({
  "name": "tiny",
  "scenes": ["sphere"],
  "materials": ["ggx:0.1"],
  "cameras": ["orbit"],
  "variants": ["none", "tk19"],
  "size": [16, 16],
  "frames": 2,
  "reference": {"spp": 1},
  "metrics": {"highlight_mask": false}
})";

const char* const kFit = R"(,
  "fit": {
    "variants": ["k16-beckmann-rect"], "param": "fp_max", "bounds": [0.01, 4], "sweep_points": 3,
    "train": {"scenes": ["sphere"], "cameras": ["orbit"]},
    "validate": {"scenes": ["sphere"], "cameras": ["pan"]}
  }
})";

std::string FitSpec(const std::string& from = "", const std::string& to = "") {
  std::string spec = std::string(kSpec);
  spec = spec.substr(0, spec.rfind('}')) + kFit;
  return from.empty() ? spec : Replace(spec, from, to);
}

std::string Spec(const std::string& from, const std::string& to) { return Replace(kSpec, from, to); }

// 10^12 jobs: 10^4 x 10^4 parameter values, 100 materials, 5 cameras, 4 scenes, 5 derivative entries.
std::string HugeSpec() {
  std::string materials;
  for (int i = 1; i <= 100; ++i)
    materials += (i > 1 ? ", " : "") + std::string("\"ggx:") + std::to_string(i / 100.0) + "\"";
  return R"({"name": "huge", "scenes": ["sphere", "sphere-field", "wires", "bumpy-plane"], "materials": [)" +
         materials + R"(], "cameras": ["orbit", "pan", "dolly", "vr-jitter", "static"],
  "variants": [{"name": "tk19", "params": {"sigma2": {"from": 0.01, "to": 1, "steps": 10000},
                                           "kappa": {"from": 0.01, "to": 1, "steps": 10000}}}],
  "derivatives": ["quad", "quad-coarse", "analytic", "quad", "analytic"], "size": [16, 16], "frames": 2})";
}

const char* const kGoodVariant =
    "// doubles the roughness\n"
    "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
    "  return evalVariant(VARIANT_NONE, ndf, alpha * real(2), f, variantParams(p));\n"
    "}\n";

// A store with finished rows, made once per test process by a real run.
const fs::path& StoreFixture() {
  static const fs::path dir = [] {
    const fs::path d = Root() / "fixture-store";
    WriteText(d / "tiny.json", kSpec);
    const std::string command =
        "cd '" + d.string() + "' && " SHIMMER_CLI " run tiny.json --db good.db --work frames >log.txt 2>&1";
    if (std::system(command.c_str()) != 0)
      throw std::runtime_error("the fixture run failed: " + ReadAll(d / "log.txt"));
    return d;
  }();
  return dir;
}

void CopyStore(const fs::path& dir, const std::string& name) {
  fs::copy_file(StoreFixture() / "good.db", dir / name);
  for (const char* suffix : {"-wal", "-shm"})
    if (fs::exists(StoreFixture() / ("good.db" + std::string(suffix))))
      fs::copy_file(StoreFixture() / ("good.db" + std::string(suffix)), dir / (name + suffix));
}

// --- the directory before and after --------------------------------------------

// Every entry under `dir`, hidden ones included: type, size and a hash of the bytes.
std::map<std::string, std::string> Tree(const fs::path& dir) {
  std::map<std::string, std::string> tree;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, fs::directory_options::none, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = fs::relative(it->path(), dir).string();
    if (it->is_symlink(ec))
      tree[name] = "link";
    else if (it->is_directory(ec))
      tree[name] = "dir";
    else
      tree[name] = "file " + std::to_string(it->file_size(ec)) + " " +
                   std::to_string(std::hash<std::string>{}(ReadAll(it->path())));
  }
  return tree;
}

std::string TreeChanges(const std::map<std::string, std::string>& before,
                        const std::map<std::string, std::string>& after) {
  std::string changes;
  for (const auto& [name, what] : after) {
    auto was = before.find(name);
    if (was == before.end())
      changes += "  new: " + name + " (" + what.substr(0, what.find(' ', 5)) + ")\n";
    else if (was->second != what)
      changes += "  changed: " + name + "\n";
  }
  for (const auto& [name, what] : before)
    if (!after.count(name)) changes += "  removed: " + name + "\n";
  return changes;
}

// --- running shimmer ------------------------------------------------------------

struct Outcome {
  int exit_code = -1;
  std::string out, err;
  double seconds = 0;
};

// `args` after "shimmer", in `dir`; `file_limit` > 0 runs it under
// `ulimit -f file_limit` (512-byte blocks), `memory_limit` > 0 under
// `ulimit -v memory_limit` (KiB). A hang ends after 120 s as exit 124.
Outcome RunShimmer(const fs::path& dir, const std::string& args, int file_limit = 0, int memory_limit = 0) {
  const fs::path out = dir.parent_path() / (dir.filename().string() + ".stdout");
  const fs::path err = dir.parent_path() / (dir.filename().string() + ".stderr");
  std::string command = "cd '" + dir.string() + "' && ";
  if (file_limit > 0) command += "ulimit -f " + std::to_string(file_limit) + " && ";
  if (memory_limit > 0) command += "ulimit -v " + std::to_string(memory_limit) + " && ";
  command += "exec timeout -k 5 120 " SHIMMER_CLI " " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  Outcome o;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  o.out = ReadAll(out);
  o.err = ReadAll(err);
  return o;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  for (char c : text) {
    if (c == '\n' || c == '\r') {
      if (!line.empty()) lines.push_back(line);
      line.clear();
    } else {
      line += c;
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// (b): one error line with `needle`, no other line that reads as an error,
// no raw library text anywhere.
void ExpectOneErrorLine(const Outcome& o, const std::string& needle) {
  const std::string prefix = "shimmer: error: ";
  std::vector<std::string> errors;
  for (const std::string& line : Lines(o.err)) {
    const std::string lower = Lower(line);
    if (line.rfind(prefix, 0) == 0) {
      errors.push_back(line);
    } else {
      for (const char* word : {"error", "exception", "terminate", "abort", "fatal", "what()"})
        EXPECT_EQ(lower.find(word), std::string::npos) << "a second error line: " << line;
    }
  }
  ASSERT_EQ(errors.size(), 1u) << "expected exactly one '" << prefix << "' line; stderr:\n" << o.err;
  EXPECT_NE(errors[0].find(needle), std::string::npos) << "the error line does not name '" << needle << "':\n"
                                                       << errors[0];
  for (const std::string& text : {o.out, o.err})
    for (const char* raw :
         {"std::", "bad_alloc", "stoi", "stod", "json.exception", "basic_string", "what():", "terminate called"})
      EXPECT_EQ(text.find(raw), std::string::npos) << "raw library text '" << raw << "':\n" << text;
}

// --- the table --------------------------------------------------------------------

struct Case {
  std::string name;                            // the test's name
  std::function<void(const fs::path&)> setup;  // the inputs, written into the case's directory
  std::string args;                            // after "shimmer"
  int exit_code;                               // 2: bad input, 1: runtime failure
  std::string message;                         // the error line contains it
  int file_limit = 0;                          // ulimit -f (512-byte blocks): a full disk
  bool needs_permissions = false;              // relies on permission bits (skipped as root)
  std::uint64_t needs_less_memory = 0;         // skipped when the machine has this many bytes available
  int memory_limit = 0;                        // ulimit -v (KiB): a regression fails, not the machine
};

// gtest prints the parameter of a failed case: the command says it all.
void PrintTo(const Case& c, std::ostream* os) { *os << "shimmer " << c.args; }

using Setup = std::function<void(const fs::path&)>;

Setup Nothing() {
  return [](const fs::path&) {};
}
Setup File(const std::string& name, const std::string& text) {
  return [=](const fs::path& d) { WriteText(d / name, text); };
}
Setup Both(Setup a, Setup b) {
  return [=](const fs::path& d) { a(d), b(d); };
}
Setup Sequence(const std::string& name, int side = 16, int frames = 2, bool noise = false) {
  return [=](const fs::path& d) { WriteSequence(d / name, side, side, frames, noise); };
}
Setup ReadOnlyDirectory(const std::string& name) {
  return [=](const fs::path& d) {
    fs::create_directories(d / name);
    fs::permissions(d / name, fs::perms::owner_read | fs::perms::owner_exec);
  };
}
Setup Store(const std::string& name) {
  return [=](const fs::path& d) { CopyStore(d, name); };
}

std::vector<Case> UnitCases() {
  const Setup spec = File("spec.json", kSpec);
  const Setup good_glsl = File("f.glsl", kGoodVariant);
  const Setup a_file = File("file", "not a directory\n");
  return {
      // variants
      {"VariantsUnknownOption", Nothing(), "variants --jsn", 2, "--jsn"},
      {"VariantsExtraArgument", Nothing(), "variants tk19", 2, "tk19"},
      {"NoSubcommand", Nothing(), "", 2, "subcommand"},
      {"UnknownSubcommand", Nothing(), "rendr", 2, "rendr"},
      // ndf
      {"NdfAlphaOutOfFloat", Nothing(), "ndf --precision float --alpha 1e39", 2, "--alpha 1e+39"},
      {"NdfAlphaNan", Nothing(), "ndf --alpha nan", 2, "--alpha"},
      {"NdfAlphaNotANumber", Nothing(), "ndf --alpha abc", 2, "--alpha"},
      {"NdfPrecision", Nothing(), "ndf --precision half", 2, "--precision"},
      {"NdfUnknownVariant", Nothing(), "ndf --variant tk20", 2, "tk20"},
      {"NdfParamOutOfRange", Nothing(), "ndf --variant k16-beckmann-rect --param fp_max=1e5", 2, "fp_max"},
      // render: flags (refused before any device is touched)
      {"RenderFramesZero", Nothing(), "render --frames 0 --size 16 16 --out out", 2, "--frames"},
      {"RenderSizeZero", Nothing(), "render --frames 2 --size 0 0 --out out", 2, "--size"},
      {"RenderSizeOneNumber", Nothing(), "render --frames 2 --size 16 --out out", 2, "--size"},
      {"RenderMaxRoundsZero", Nothing(),
       "render --frames 2 --size 16 16 --reference-tolerance 0.1 --max-rounds 0 --out out", 2, "--max-rounds"},
      {"RenderMaxRoundsNegative", Nothing(), "render --frames 2 --size 16 16 --max-rounds -1 --out out", 2,
       "--max-rounds"},
      {"RenderReplicatesOne", Nothing(),
       "render --frames 2 --size 16 16 --reference-spp 2 --reference-replicates 1 --out out", 2,
       "--reference-replicates must be in 2..4096"},
      {"RenderSeedNegative", Nothing(), "render --frames 2 --size 16 16 --seed -1 --out out", 2, "--seed"},
      {"RenderFpsNan", Nothing(), "render --frames 2 --size 16 16 --fps nan --out out", 2, "--fps"},
      {"RenderFramesNotANumber", Nothing(), "render --frames two --size 16 16 --out out", 2, "--frames"},
      {"RenderFramesOverflow", Nothing(), "render --frames 99999999999 --size 16 16 --out out", 2, "--frames"},
      {"RenderParamNan", good_glsl, "render --frames 2 --size 16 16 --variant-file f.glsl --param fp_max=nan --out out",
       2, "--param fp_max"},
      {"RenderParamNegative", good_glsl,
       "render --frames 2 --size 16 16 --variant-file f.glsl --param fp_max=-5 --out out", 2, "fp_max"},
      {"RenderSupersampleHuge", Nothing(), "render --frames 2 --size 16 16 --variant supersample-99999999999 --out out",
       2, "supersample-99999999999"},
      {"RenderVariantAndVariantFile", good_glsl,
       "render --frames 2 --size 16 16 --variant tk19 --variant-file f.glsl --out out", 2, "--variant-file f.glsl"},
      {"RenderMissingVariantFile", Nothing(), "render --frames 2 --size 16 16 --variant-file nope.glsl --out out", 2,
       "nope.glsl"},
      {"RenderGlslSyntaxError",
       File("syntax.glsl",
            "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, "
            "UserParams p) {\n  return evalVariant(VARIANT_NONE, ndf alpha, f, variantParams(p))\n}\n"),
       "render --frames 2 --size 16 16 --variant-file syntax.glsl --out out", 2, "syntax.glsl:2"},
      {"RenderGlslWrongSignature", File("sig.glsl", "float userVariant(vec2 alpha) {\n  return alpha.x;\n}\n"),
       "render --frames 2 --size 16 16 --variant-file sig.glsl --out out", 2, "sig.glsl"},
      {"RenderGlslNoUserVariant", File("none.glsl", "// nothing here\n"),
       "render --frames 2 --size 16 16 --variant-file none.glsl --out out", 2, "none.glsl"},
      // export-blender
      {"ExportBlenderUnknownScene", Nothing(), "export-blender sphre -o s.py", 2, "sphre"},
      {"ExportBlenderFrameOutOfRange", Nothing(), "export-blender sphere --frames 4 --frame 4 -o s.py", 2, "--frame 4"},
      {"ExportBlenderFrameNegative", Nothing(), "export-blender sphere --frame -1 -o s.py", 2, "--frame -1"},
      {"ExportBlenderOutMissingDirectory", Nothing(), "export-blender sphere -o nodir/s.py", 2, "nodir"},
      {"ExportBlenderOutIsADirectory", ReadOnlyDirectory("d"), "export-blender sphere -o d", 2, "-o d"},
      {"ExportBlenderBumpyPlane", Nothing(), "export-blender bumpy-plane -o s.py", 2, "bump"},
      {"ExportBlenderAnisotropic", Nothing(), "export-blender sphere --material ggx:0.1,0.3 -o s.py", 2, "anisotropic"},
      {"ExportBlenderSizeZero", Nothing(), "export-blender sphere --size 0 8 -o s.py", 2, "--size"},
      // render: scene files
      {"SceneMalformedJson", File("s.json", "{\"primitives\": [{\"type\": \"sphere\", }]}\n"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "s.json:1"},
      {"SceneSphereWithoutCenter", File("s.json", R"({"primitives": [{"type": "sphere", "radius": 1}]})"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "center"},
      {"SceneWrongType",
       File("s.json", R"({"primitives": [{"type": "sphere", "center": [0, 0, 0], "radius": "big"}]})"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "radius"},
      {"SceneCenterWrongType", File("s.json", R"({"primitives": [{"type": "sphere", "center": "origin"}]})"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "center"},
      {"SceneNumberOverflow", File("s.json", R"({"primitives": [{"type": "sphere", "center": [0, 1e999, 0]}]})"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "number out of range"},
      {"SceneUnknownKey", File("s.json", R"({"primitives": [{"type": "sphere", "center": [0, 0, 0], "colour": 1}]})"),
       "render --scene s.json --frames 2 --size 16 16 --out out", 2, "colour"},
      {"SceneNotAnObject", File("s.json", "[1, 2, 3]\n"), "render --scene s.json --frames 2 --size 16 16 --out out", 2,
       "s.json"},
      // scene validate / preview: the same reader, its JSON Pointer in the one line
      {"SceneValidateBadRadius",
       File("s.json", R"({"primitives": [{"type": "sphere", "center": [0, 0, 0], "radius": -1}]})"),
       "scene validate s.json", 2, "s.json: /primitives/0/radius: must be a number > 0"},
      {"SceneValidateUnknownLightKey",
       File("s.json", R"({"primitives": [{"type": "plane"}], "light": {"direction": [0, 1, 0], "colour": 1}})"),
       "scene validate s.json", 2, "s.json: /light/colour: unknown key"},
      {"SceneValidateMissingFile", Nothing(), "scene validate nowhere.json", 2, "nowhere.json"},
      // scene validate on a mesh asset: the loader's one error naming the file
      {"SceneValidateAssetMissing", Nothing(), "scene validate gone.glb", 2, "gone.glb"},
      {"SceneValidateAssetTruncatedGlb", File("t.glb", "glTF\x02\x00\x00\x00"), "scene validate t.glb", 2, "t.glb"},
      {"SceneValidateAssetBadIndex", File("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
       "scene validate bad.obj", 2, "bad.obj"},
      {"SceneValidateAssetNoTriangles", File("empty.obj", "v 0 0 0\n"), "scene validate empty.obj", 2, "empty.obj"},
      {"SceneValidateNoFile", Nothing(), "scene validate", 2, "scene is required"},
      {"SceneNoAction", Nothing(), "scene", 2, "subcommand"},
      {"ScenePreviewBadScene", File("s.json", R"({"primitives": [{"type": "cube"}]})"), "scene preview s.json -o p.png",
       2, "s.json: /primitives/0/type: unknown type 'cube'"},
      {"ScenePreviewNoOutput", Nothing(), "scene preview sphere", 2, "--out is required"},
      {"ScenePreviewOutMissingDirectory", Nothing(), "scene preview sphere -o nodir/p.png", 2, "nodir"},
      {"ScenePreviewSizeZero", Nothing(), "scene preview sphere --size 0 8 -o p.png", 2, "--size"},
      {"ScenePreviewFrameNegative", Nothing(), "scene preview sphere --frame -1 -o p.png", 2, "--frame"},
      {"ScenePreviewBadCamera", Nothing(), "scene preview sphere --camera spin -o p.png", 2, "--camera"},
      {"ScenePreviewBadMaterial", Nothing(), "scene preview sphere --material ggx:7 -o p.png", 2, "material"},
      // render: where it writes (refused before any device is touched)
      {"RenderOutUnderAFile", a_file, "render --frames 2 --size 16 16 --out file/out", 2, "file/out"},
      {"RenderPreviewUnderAFile", a_file, "render --frames 2 --size 16 16 --preview file/p.png --out out", 2,
       "--preview"},
      // Two frames of 16384 x 16384 x 21 floats do not fit: refused before the device, as out of memory.
      {"RenderSizeHuge", Nothing(), "render --scene sphere --frames 2 --size 16384 16384 --out out", 1, "16384x16384",
       16, false, 2ull * 16384 * 16384 * 21 * 4, 4000000},
      {"RenderOutReadOnly", ReadOnlyDirectory("ro"), "render --frames 2 --size 16 16 --out ro/out", 1, "ro/out", 0,
       true},
      // metrics
      {"MetricsNotAnExr", Both(Sequence("seq"), File("seq/frame_0000.exr", "not an EXR file\n")), "metrics seq", 2,
       "frame_0000.exr"},
      {"MetricsTruncatedExr",
       Both(Sequence("seq"),
            [](const fs::path& d) {
              fs::resize_file(d / "seq/frame_0001.exr", fs::file_size(d / "seq/frame_0001.exr") / 2);
            }),
       "metrics seq", 2, "frame_0001.exr"},
      {"MetricsForgedDataWindow",
       Both(Sequence("seq"), [](const fs::path& d) { ForgeDataWindow(d / "seq/frame_0000.exr"); }), "metrics seq", 2,
       "100000x100000", 0, false, 0, 2000000},
      {"MetricsSizeMismatch", Both(Sequence("test", 16), Sequence("ref", 8)), "metrics test ref", 2, "8x8"},
      {"MetricsMissingLayer", Sequence("seq"), "metrics seq --layer diffuse", 2, "diffuse"},
      {"MetricsFailedSequence",
       Both(Sequence("seq"), File("seq/sequence.json", R"({"status": "failed", "error": "frame 2: device lost",
         "fps": 30, "frames": ["frame_0000.exr", "frame_0001.exr"]})")),
       "metrics seq/sequence.json", 2, "failed"},
      {"MetricsNoSuchSequence", Nothing(), "metrics nowhere", 2, "nowhere"},
      {"MetricsEmptyDirectory", [](const fs::path& d) { fs::create_directories(d / "empty"); }, "metrics empty", 2,
       "empty"},
      {"MetricsOneFrame", Sequence("seq", 16, 1), "metrics seq", 2, "seq"},
      {"MetricsHighlightDilateHuge", Both(Sequence("test"), Sequence("ref")),
       "metrics test ref --highlight-mask --highlight-dilate 1e8", 2, "--highlight-dilate"},
      {"MetricsFpsNan", Sequence("seq"), "metrics seq --fps nan", 2, "--fps"},
      {"MetricsSegmentOne", Sequence("seq"), "metrics seq --segment 1", 2, "--segment"},
      {"MetricsSignal", Sequence("seq"), "metrics seq --signal noise", 2, "--signal"},
      {"MetricsMaskAndHighlight", Both(Sequence("test"), Sequence("ref")),
       "metrics test ref --mask m.png --highlight-mask", 2, "--mask"},
      {"MetricsOutUnderAFile", Both(Sequence("seq"), a_file), "metrics seq --out file/maps", 2, "file/maps"},
      {"MetricsVideoUnderAFile", Both(Both(Sequence("test"), Sequence("ref")), a_file),
       "metrics test ref --video file/v.mp4", 2, "file/v.mp4"},
      {"MetricsOutFullDisk", Sequence("big", 64, 4, true), "metrics big big --out maps", 1, "File too large", 16},
      {"MetricsOutReadOnly", Both(Sequence("seq"), ReadOnlyDirectory("ro")), "metrics seq --out ro/maps", 1, "ro/maps",
       0, true},
      // run: spec files
      {"RunNoSuchSpec", Nothing(), "run nope.json", 2, "nope.json"},
      {"RunMalformedJson", File("spec.json", Spec("\"frames\": 2,", "\"frames\": 2,,")), "run spec.json", 2,
       "spec.json:8:15"},
      {"RunWrongType", File("spec.json", Spec("\"frames\": 2", "\"frames\": \"2\"")), "run spec.json", 2, "frames"},
      {"RunUnknownKey", File("spec.json", Spec("\"frames\": 2", "\"framez\": 2")), "run spec.json", 2, "framez"},
      {"RunNameDotDot", File("spec.json", Spec("\"tiny\"", "\"../../x\"")), "run spec.json", 2, "name"},
      {"RunNameSlash", File("spec.json", Spec("\"tiny\"", "\"a/b\"")), "run spec.json", 2, "name"},
      {"RunNumberOverflow", File("spec.json", Spec("\"frames\": 2", "\"fps\": 1e999, \"frames\": 2")), "run spec.json",
       2, "number out of range"},
      {"RunFramesHuge", File("spec.json", Spec("\"frames\": 2", "\"frames\": 1048576")), "run spec.json", 2, "frames"},
      {"RunCrossProduct", File("spec.json", HugeSpec()), "run spec.json", 2, "jobs"},
      {"RunUnknownVariant", File("spec.json", Spec("\"tk19\"", "\"tk20\"")), "run spec.json", 2, "tk20"},
      {"RunGgxOnlyVariantOnBeckmann",
       File("spec.json", Replace(Spec("\"ggx:0.1\"", "\"beckmann:0.1\""), "\"tk19\"", "\"k16-ggx-rect\"")),
       "run spec.json", 2, "GGX"},
      {"RunShard", spec, "run spec.json --shard 3/2", 2, "--shard"},
      {"RunJobsZero", spec, "run spec.json --jobs 0", 2, "--jobs"},
      {"RunDbUnderAFile", Both(spec, a_file), "run spec.json --db file/r.db --work frames", 2, "file/r.db"},
      {"RunWorkUnderAFile", Both(spec, a_file), "run spec.json --db r.db --work file/frames", 2, "file/frames"},
      {"RunDbNotAStore", Both(spec, File("r.db", "not a database, just text\n")),
       "run spec.json --db r.db --work frames", 2, "r.db"},
      {"RunDbReadOnly", Both(spec, ReadOnlyDirectory("ro")), "run spec.json --db ro/r.db --work frames", 1, "ro/r.db",
       0, true},
      // fit
      {"FitNoFitSection", spec, "fit spec.json", 2, "\"fit\""},
      {"FitSweepPointsHuge", File("spec.json", FitSpec("\"sweep_points\": 3", "\"sweep_points\": 1048576")),
       "fit spec.json", 2, "sweep_points"},
      {"FitBoundsReversed", File("spec.json", FitSpec("[0.01, 4]", "[4, 0.01]")), "fit spec.json", 2, "bounds"},
      {"FitParamUnknown", File("spec.json", FitSpec("\"param\": \"fp_max\"", "\"param\": \"sigma2\"")), "fit spec.json",
       2, "sigma2"},
      {"FitUnknownKey", File("spec.json", FitSpec("\"sweep_points\": 3", "\"sweep_pts\": 3")), "fit spec.json", 2,
       "sweep_pts"},
      {"FitOutUnderAFile", Both(File("spec.json", FitSpec()), a_file), "fit spec.json --db f.db --work w -o file/rep",
       2, "file/rep"},
      {"FitDbUnderAFile", Both(File("spec.json", FitSpec()), a_file), "fit spec.json --db file/f.db --work w", 2,
       "file/f.db"},
      {"FitFromJsonMissing", File("spec.json", FitSpec()), "fit spec.json --from-json gone.json -o rep", 2,
       "gone.json"},
      {"FitFromJsonForeign", Both(File("spec.json", FitSpec()), File("f.json", "{\"fitz\": []}\n")),
       "fit spec.json --from-json f.json -o rep", 2, "not a fit.json"},
      // merge
      {"MergeNoSuchStore", Nothing(), "merge a.db -o all.db", 2, "a.db"},
      {"MergeNotAStore", File("a.db", "just text\n"), "merge a.db -o all.db", 2, "a.db"},
      {"MergeOutputUnderAFile", Both(File("a.db", "just text\n"), a_file), "merge a.db -o file/all.db", 2,
       "file/all.db"},
      {"MergeNoOutput", Nothing(), "merge a.db", 2, "--output"},
      // prune
      {"PruneNoSuchStore", Nothing(), "prune a.db", 2, "a.db: no such results store"},
      {"PruneNotAStore", File("a.db", "just text\n"), "prune a.db --dry-run", 2, "a.db"},
      // sweep (refused before any render)
      {"SweepParamShape", Nothing(), "sweep --param fp_max=0.1:1", 2, "--param"},
      {"SweepParamSteps", Nothing(), "sweep --param fp_max=0.1:1:100000 --size 16 16 --frames 2", 2, "steps"},
      {"SweepParamUnknown", Nothing(), "sweep --param sigma2=0.1:1:3 --size 16 16 --frames 2", 2, "sigma2"},
      {"SweepSizeZero", Nothing(), "sweep --param fp_max=0.1:1:2 --size 0 0 --frames 2", 2, "--size"},
      {"SweepFramesOne", Nothing(), "sweep --param fp_max=0.1:1:2 --size 16 16 --frames 1", 2, "--frames"},
      {"SweepCsvUnderAFile", a_file, "sweep --param fp_max=0.1:1:2 --size 16 16 --frames 2 --csv file/s.csv", 2,
       "file/s.csv"},
      {"SweepCsvReadOnly", ReadOnlyDirectory("ro"),
       "sweep --param fp_max=0.1:1:2 --size 16 16 --frames 2 --csv ro/s.csv --work w", 1, "ro/s.csv", 0, true},
      {"SweepWorkUnderAFile", a_file, "sweep --param fp_max=0.1:1:2 --size 16 16 --frames 2 --work file/w", 2,
       "file/w"},
      // report
      {"ReportNoSuchStore", Nothing(), "report nope.db -o rep", 2, "nope.db"},
      {"ReportNotAStore", File("r.db", "just text\n"), "report r.db -o rep", 2, "r.db"},
      {"ReportNoOutput", Nothing(), "report r.db", 2, "--output"},
      // sg-accuracy (refused before the measurement)
      {"SgAccuracyViewNinety", Nothing(), "sg-accuracy --view 30 90", 2, "--view must be in [0, 90), got 90"},
      {"SgAccuracySamplesTooFew", Nothing(), "sg-accuracy --samples 2", 2, "--samples"},
      {"SgAccuracyAlphaNan", Nothing(), "sg-accuracy --alpha 0.1,nan", 2, "--alpha"},
      {"SgAccuracyOutUnderAFile", a_file, "sg-accuracy --samples 4 -o file/out", 2, "file/out"},
  };
}

// Cases that render (or need a store a real run made).
std::vector<Case> GpuCases() {
  const Setup a_file = File("file", "not a directory\n");
  return {
      {"RenderFullDisk", Nothing(), "render --scene sphere --frames 2 --size 32 32 --out out", 1, "File too large", 16},
      {"RenderPreviewFullDisk", Nothing(), "render --scene sphere --frames 2 --size 96 96 --preview p.png --out out", 1,
       "File too large", 16},
      // 2 x 2 frames fit under the limit, the plot does not.
      {"SweepCsvFullDisk", Nothing(),
       "sweep --scene sphere --param fp_max=0.1:1:2 --size 2 2 --frames 2 --reference-spp 1 --csv s.csv --work w", 1,
       "s.svg: cannot write the plot", 8},
      {"ReportFullDisk", Store("good.db"), "report good.db -o rep", 1, "cannot write the plot", 16},
      {"ReportOutputUnderAFile", Both(Store("good.db"), a_file), "report good.db -o file/rep", 2, "file/rep"},
      {"ReportOutputReadOnly", Both(Store("good.db"), ReadOnlyDirectory("ro")), "report good.db -o ro/rep", 1, "ro/rep",
       0, true},
      {"MergeOutputReadOnly", Both(Store("a.db"), ReadOnlyDirectory("ro")), "merge a.db -o ro/all.db", 1, "ro/all.db",
       0, true},
      {"MergeFullDisk", Store("a.db"), "merge a.db -o all.db", 1, "File too large", 16},
      {"MergeEmptyStore", Both(Store("a.db"), File("empty.db", "")), "merge a.db empty.db -o all.db", 2, "empty.db"},
      {"RunFullDisk", File("spec.json", kSpec), "run spec.json --db r.db --work frames", 1, "File too large", 16},
  };
}

void RunCase(const Case& c) {
  if (c.needs_permissions && ::geteuid() == 0) GTEST_SKIP() << "running as root: permission bits do not stop writes";
  if (c.needs_less_memory && shimmer::AvailableHostMemory() >= c.needs_less_memory)
    GTEST_SKIP() << "this machine has the memory: the render would go ahead";
  const fs::path dir = Root() / c.name;
  fs::create_directories(dir);
  c.setup(dir);
  const auto before = Tree(dir);
  const Outcome o = RunShimmer(dir, c.args, c.file_limit, c.memory_limit);
  SCOPED_TRACE("shimmer " + c.args + (c.file_limit ? " (ulimit -f " + std::to_string(c.file_limit) + ")" : "") +
               (c.memory_limit ? " (ulimit -v " + std::to_string(c.memory_limit) + ")" : "") + "\nstdout:\n" + o.out +
               "stderr:\n" + o.err);
  std::string shown;
  for (const std::string& line : Lines(o.err))
    if (shown.empty() || line.rfind("shimmer: error: ", 0) == 0) shown = line;
  std::printf("shimmer %s -> exit %d: %s\n", c.args.c_str(), o.exit_code, shown.c_str());
  EXPECT_EQ(o.exit_code, c.exit_code);
  ExpectOneErrorLine(o, c.message);
  EXPECT_EQ(TreeChanges(before, Tree(dir)), "") << "the directory changed";
  EXPECT_LT(o.seconds, 60) << "took " << o.seconds << " s";
}

class BadInput : public ::testing::TestWithParam<Case> {};
TEST_P(BadInput, OneErrorLineAndNothingWritten) { RunCase(GetParam()); }
INSTANTIATE_TEST_SUITE_P(Cli, BadInput, ::testing::ValuesIn(UnitCases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

class GpuBadInput : public ::testing::TestWithParam<Case> {};
TEST_P(GpuBadInput, OneErrorLineAndNothingWritten) { RunCase(GetParam()); }
INSTANTIATE_TEST_SUITE_P(Cli, GpuBadInput, ::testing::ValuesIn(GpuCases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

// Two `shimmer run` on one store: while the first holds the store's lock, the
// second fails at once (exit 1: the request is fine, it cannot be done now),
// and the first finishes its jobs undisturbed.
TEST(GpuRunLock, SecondRunnerOnOneStoreFailsAtOnce) {
  const fs::path dir = Root() / "RunLock";
  std::string spec = kSpec;
  spec =
      Replace(spec, "[\"none\", \"tk19\"]", "[\"none\", \"tk19\", \"tk21\", \"filament\", \"godot\", \"vlachos15\"]");
  WriteText(dir / "spec.json", spec);
  const pid_t first = fork();
  ASSERT_GE(first, 0);
  if (first == 0) {
    const std::string command =
        "cd '" + dir.string() + "' && exec " SHIMMER_CLI " run spec.json --db r.db --work frames >first.log 2>&1";
    execl("/bin/sh", "sh", "-c", command.c_str(), nullptr);
    _exit(127);
  }
  // The lock is the first thing the runner takes after reading the spec.
  bool held = false;
  for (int i = 0; i < 3000 && !held; ++i) {
    const int fd = ::open((dir / "r.db.lock").c_str(), O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
      held = ::flock(fd, LOCK_EX | LOCK_NB) != 0;
      if (!held) ::flock(fd, LOCK_UN);
      ::close(fd);
    }
    if (!held) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(held) << "the first runner never took the lock: " << ReadAll(dir / "first.log");
  const fs::path second_dir = dir / "second";
  fs::create_directories(second_dir);
  const Outcome o = RunShimmer(second_dir, "run ../spec.json --db ../r.db --work ../frames");
  int status = 0;
  waitpid(first, &status, 0);
  SCOPED_TRACE("stderr of the second:\n" + o.err + "log of the first:\n" + ReadAll(dir / "first.log"));
  EXPECT_EQ(o.exit_code, 1);
  ExpectOneErrorLine(o, "another shimmer process");
  EXPECT_LT(o.seconds, 10);
  EXPECT_TRUE(fs::is_empty(second_dir));
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_NE(ReadAll(dir / "first.log").find("(6 computed, 0 already done)"), std::string::npos);
}

}  // namespace

// `scene validate` on a good file: exit 0 and one line of what it holds.
TEST(SceneCli, ValidatePrintsWhatTheFileHolds) {
  const fs::path dir = Root() / "SceneValidate";
  WriteText(dir / "s.json", R"({"name": "two", "primitives": [{"type": "sphere", "center": [0, 1, 0], "radius": 0.5},
    {"type": "capsule", "a": [0, 0, 0], "b": [1, 0, 0]}, {"type": "plane"}], "light": {"type": "sg", "axis": [0, 1, 0],
    "sharpness": 20, "amplitude": [1, 1, 1]}, "material": "beckmann:0.2"})");
  const Outcome o = RunShimmer(dir, "scene validate s.json");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(o.err, "");
  EXPECT_NE(o.out.find("s.json: valid scene 'two': 3 primitives (1 spheres, 1 capsules, 1 planes), sg light, "
                       "material beckmann:0.2"),
            std::string::npos)
      << o.out;
}

// `scene validate` on a mesh asset: exit 0, what it holds, and each
// loader warning (computed normals, a zero-area triangle) on stderr.
TEST(SceneCli, ValidateAnAssetPrintsItsMeshesAndWarnings) {
  const fs::path dir = Root() / "SceneValidateAsset";
  WriteText(dir / "quad.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 5 5 5\n"
                              "f 1 2 3\nf 1 3 4\nf 5 5 5\n");
  const Outcome o = RunShimmer(dir, "scene validate quad.obj");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("quad.obj: valid asset: 1 meshes, 3 triangles"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("bounds (0, 0, 0) to (5, 5, 5)"), std::string::npos) << o.out;
  EXPECT_NE(o.err.find("normals computed"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("zero area"), std::string::npos) << o.err;
}

// `scene preview`: a PNG of the requested size, written whole under its name.
TEST(GpuSceneCli, PreviewWritesAPngOfTheRequestedSize) {
  const fs::path dir = Root() / "ScenePreview";
  WriteText(dir / "s.json", R"({"primitives": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})");
  const Outcome o = RunShimmer(dir, "scene preview s.json -o p.png --size 40 24 --frame 3");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string bytes = ReadAll(dir / "p.png");
  ASSERT_GT(bytes.size(), 24u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  auto be32 = [&](size_t at) {
    return (uint32_t(uint8_t(bytes[at])) << 24) | (uint32_t(uint8_t(bytes[at + 1])) << 16) |
           (uint32_t(uint8_t(bytes[at + 2])) << 8) | uint32_t(uint8_t(bytes[at + 3]));
  };
  EXPECT_EQ(be32(16), 40u);  // IHDR width
  EXPECT_EQ(be32(20), 24u);  // IHDR height
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"p.png", "s.json"})) << "no temporary file left behind";
}
