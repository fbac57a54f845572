// Runs a spec's jobs: renders each shared reference once, renders each job,
// measures it with the metrics library and stores one row per job. Finished
// jobs (by id) are skipped, so a run killed at any point resumes losing
// nothing: frames are rendered into "*.partial" directories and renamed only
// when complete, and a row is committed only after its metrics exist.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "job.h"
#include "result_store.h"
#include "spec.h"

namespace shimmer::experiments {

struct RunProgress {
  int done = 0;     // jobs finished in this run (skipped ones included)
  int total = 0;
  int skipped = 0;  // found finished in the store
  double elapsed_s = 0;
  double eta_s = 0;  // from the mean time of the jobs computed so far
  std::string current;
};

struct RunOptions {
  std::string db_path;          // results store
  std::string work_dir;         // frame cache: references and jobs by id
  int shard_index = 0, shard_count = 1;
  bool keep_frames = false;
  int jobs = 1;                 // jobs measured at once (each renders, then measures)
  std::string device;           // Vulkan device name substring
  std::function<void(const RunProgress&)> progress;
};

struct RunSummary {
  int total = 0, skipped = 0, computed = 0;
  std::string error;  // empty when every job finished
};

RunSummary RunJobs(const std::vector<Job>& jobs, const RunOptions& options);

// One job, measured against its reference (rendered on demand), as the row the
// store keeps. Used by the runner and by sweeps and fits.
struct Measured {
  JobResult result;
  std::string error;
};
Measured MeasureJob(const Job& job, const RunOptions& options);

// Renders the job's reference into the cache unless it is there; returns an error message.
std::string EnsureReference(const Job& job, const RunOptions& options);

}  // namespace shimmer::experiments
