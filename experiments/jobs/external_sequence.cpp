// An external sequence of a spec (section "sequences"): the frames are
// opened and hashed when the spec is read, so that a missing frame, a size
// mismatch or a changed file is found before any work.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include "shimmer/core/content_hash.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/metrics/exr_sequence.h"

namespace shimmer::experiments {

namespace {

Result<std::string> FileHash(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  if (!in && !in.eof()) return Result<std::string>::Failure(file.string() + ": cannot read the frame", ErrorCode::kIo);
  return Fnv1a64Hex(bytes.str());
}

}  // namespace

Result<std::string> SequenceContentHash(const std::string& path) {
  auto sequence = metrics::OpenSequence(path, {});
  if (!sequence) return sequence.failure();
  // One hash per frame, then one of the list: a frame at a time in memory.
  std::string list = sequence->layer + "\n";
  for (const std::filesystem::path& frame : sequence->frames) {
    auto hash = FileHash(frame);
    if (!hash) return hash;
    list += frame.filename().string() + " " + *hash + "\n";
  }
  return Fnv1a64Hex(list);
}

Result<ExternalSequence> OpenExternalSequence(ExternalSequence sequence, std::string* bad_key) {
  using R = Result<ExternalSequence>;
  metrics::SequenceRequest request;
  if (sequence.fps > 0) request.fps = sequence.fps;
  auto test = metrics::OpenSequence(sequence.files.test, request);
  if (!test) return *bad_key = "test", test.failure();
  auto reference = metrics::OpenSequence(sequence.files.reference, request);
  if (!reference) return *bad_key = "reference", reference.failure();
  *bad_key = "reference";
  if (reference->width != test->width || reference->height != test->height)
    return R::Failure(sequence.files.reference + " is " + std::to_string(reference->width) + "x" +
                      std::to_string(reference->height) + " and the test sequence " + sequence.files.test + " " +
                      std::to_string(test->width) + "x" + std::to_string(test->height) + "; they must be the same size");
  if (reference->frames.size() != test->frames.size())
    return R::Failure(sequence.files.reference + " has " + std::to_string(reference->frames.size()) +
                      " frames and the test sequence " + sequence.files.test + " " +
                      std::to_string(test->frames.size()) + "; they must be as long");
  if (test->frames.size() < 2) return *bad_key = "test", R::Failure(sequence.files.test + ": temporal metrics need at least 2 frames");
  sequence.width = test->width;
  sequence.height = test->height;
  sequence.frames = int(test->frames.size());
  for (auto [key, path, hash] : {std::tuple{"test", &sequence.files.test, &sequence.files.test_hash},
                                 std::tuple{"reference", &sequence.files.reference, &sequence.files.reference_hash}}) {
    auto content = SequenceContentHash(*path);
    if (!content) return *bad_key = key, content.failure();
    *hash = *content;
  }
  bad_key->clear();
  return sequence;
}

}  // namespace shimmer::experiments
