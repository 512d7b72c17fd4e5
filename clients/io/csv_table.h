// Minimal CSV for our own numeric tables: comma separated, one header line, no quoting
// (none of our fields contain commas). Columns are found by header name, so readers keep
// working when columns are added or reordered.
#pragma once

#include <string>
#include <vector>

#include "engine/core/status.h"

namespace localizer::io {

class CsvTable {
 public:
  // Reads `path`; blank lines are skipped; every row must have the header's field count.
  static StatusOr<CsvTable> Read(const std::string& path);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& header() const { return header_; }
  size_t row_count() const { return rows_.size(); }

  // Index of the column named `name`, or INVALID_ARGUMENT naming the file and column.
  StatusOr<int> Column(const std::string& name) const;
  const std::string& Text(size_t row, int column) const { return rows_[row].fields[column]; }
  // The field parsed as a double ("nan" and "inf" accepted); the error names the file,
  // line and column.
  StatusOr<double> Number(size_t row, int column) const;

 private:
  struct Row {
    int line = 0;  // 1-based line in the file, for messages
    std::vector<std::string> fields;
  };
  std::string path_;
  std::vector<std::string> header_;
  std::vector<Row> rows_;
};

// Appends `value` with 10 significant digits (enough for microseconds over hours and
// micrometres over kilometres); non-finite values as "nan", "inf", "-inf".
void AppendNumber(double value, std::string* out);
// A comma, then `value` as AppendNumber writes it, or nothing for NaN (a field the data do
// not give): one more field of a row.
void AppendField(double value, std::string* line);

}  // namespace localizer::io
