// `shimmer video TEST... [--reference REF] -o grid.mp4`: several sequences
// side by side, labelled, each above its signed error against the reference,
// with a legend; optional slow motion.
#include <cstdio>

#include "commands.h"
#include "shimmer/metrics/video_grid.h"

namespace shimmer::cli {

namespace {

struct VideoCliOptions {
  std::vector<std::string> tests, labels;
  std::string reference, layer, out;
  double fps = 0;
  int slow = 1;
};

void Run(const VideoCliOptions& o) {
  metrics::GridSequences in;
  for (const std::string& t : o.tests) in.tests.push_back(t);
  const int most = metrics::VideoGrid::kMaxTiles - 1;
  if (int(o.tests.size()) > most)
    throw UsageError("at most " + std::to_string(most) + " test sequences fit a grid (with the reference's tile), got " +
                     std::to_string(o.tests.size()));
  if (!o.labels.empty() && o.labels.size() != o.tests.size())
    throw UsageError("--label must be given once per test sequence (" + std::to_string(o.tests.size()) + "), got " +
                     std::to_string(o.labels.size()));
  in.labels = o.labels;
  in.reference = o.reference;
  in.request.layer = o.layer;
  if (o.fps != 0) {
    if (!(o.fps > 0) || o.fps > 1e6) throw UsageError("--fps must be in (0, 1e6], got " + std::to_string(o.fps));
    in.request.fps = o.fps;
  }
  if (o.slow < 1 || o.slow > 100) throw UsageError("--slow must be 1..100, got " + std::to_string(o.slow));
  in.slow = o.slow;
  RequireParentDirectory("--output", o.out);
  const metrics::GridVideoWritten written = Take(metrics::WriteGridVideo(in, o.out));
  std::printf("wrote %s: %d tiles, %d frames (MP4, %s)\n", o.out.c_str(), written.tiles, written.frames,
              written.fourcc.c_str());
}

}  // namespace

void AddVideoCommand(CLI::App& app) {
  auto o = std::make_shared<VideoCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "video", "A labelled grid MP4 of up to 8 sequences and their reference, errors below, with a legend");
  cmd->add_option("TEST", o->tests, "Test sequences: directories of EXR frames or sequence.json files")->required();
  cmd->add_option("--reference", o->reference, "Reference sequence: each test's signed error against it");
  cmd->add_option("--label", o->labels, "Tile label, once per test in order (default: directory names)");
  cmd->add_option("--layer", o->layer, "EXR layer to show (default: specular when present, else beauty R,G,B)");
  cmd->add_option("--fps", o->fps, "Frame rate when sequence.json gives none (default 60)");
  cmd->add_option("--slow", o->slow, "Write each frame N times (slow motion)")->capture_default_str();
  cmd->add_option("-o,--output", o->out, "MP4 file to write")->required();
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
