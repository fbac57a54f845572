#include "shimmer/experiments/csv.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace shimmer::experiments {

std::string CsvField(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string CsvNumber(double value) {
  if (std::isnan(value)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", value);
  return buf;
}

CsvTable::CsvTable(std::vector<std::string> header) : columns_(header.size()) { Append(header); }

void CsvTable::AddRow(const std::vector<std::string>& fields) {
  if (fields.size() != columns_)
    throw std::logic_error("CSV row of " + std::to_string(fields.size()) + " fields under a header of " +
                           std::to_string(columns_));
  Append(fields);
}

void CsvTable::Append(const std::vector<std::string>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) text_ += (i ? "," : "") + CsvField(fields[i]);
  text_ += "\r\n";
}

}  // namespace shimmer::experiments
