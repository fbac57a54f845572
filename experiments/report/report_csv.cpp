#include "report_parts.h"
#include "shimmer/experiments/csv.h"

namespace shimmer::experiments::report {

std::string Csv(const std::vector<JobResult>& rows) {
  CsvTable table({"scene", "material", "camera", "variant", "params", "derivatives", "region", "tv_ratio", "tv_err",
                  "energy_bias", "temporal_diff_err", "relmse", "flicker_index", "ms_per_frame", "device", "driver"});
  for (const JobResult& r : rows) {
    const auto& m = r.metrics;
    table.AddRow({r.job.scene, r.job.material, r.job.camera, r.job.variant, nlohmann::json(r.job.params).dump(),
                  r.job.derivatives, Region(r), CsvNumber(Metric(m, "tv_ratio")), CsvNumber(Metric(m, "tv_err")),
                  CsvNumber(Metric(m, "energy_bias")), CsvNumber(Metric(m, "temporal_diff_err")),
                  CsvNumber(Metric(m, "relmse")), CsvNumber(FlickerIndex(m)), CsvNumber(r.gpu_ms_per_frame), r.device,
                  r.driver});
  }
  return table.Text();
}

}  // namespace shimmer::experiments::report
