// CSV as RFC 4180 writes it: fields holding a comma, a quote or a line break
// are quoted, quotes inside doubled. Spreadsheets, pandas and Python's csv
// module read it back field for field.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace shimmer::experiments {

std::string CsvField(std::string_view text);
// Shortest round-trip-safe text with 6 significant digits ("%.6g"); empty for NaN.
std::string CsvNumber(double value);

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> header);
  // A row with as many fields as the header (checked: a short row would shift columns).
  void AddRow(const std::vector<std::string>& fields);
  const std::string& Text() const { return text_; }

 private:
  void Append(const std::vector<std::string>& fields);
  std::size_t columns_;
  std::string text_;
};

}  // namespace shimmer::experiments
