#include "clients/io/csv_table.h"

#include <charconv>
#include <cmath>
#include <fstream>

namespace localizer::io {

namespace {

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const size_t end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

}  // namespace

StatusOr<CsvTable> CsvTable::Read(const std::string& path) {
  std::ifstream in(path);
  if (!in) return NotFound(path + ": cannot open");
  CsvTable table;
  table.path_ = path;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    std::vector<std::string> fields = SplitFields(line);
    if (table.header_.empty()) {
      table.header_ = std::move(fields);
      continue;
    }
    if (fields.size() != table.header_.size()) {
      return InvalidArgument(path + ":" + std::to_string(line_number) + ": " + std::to_string(fields.size()) +
                             " fields, the header has " + std::to_string(table.header_.size()));
    }
    table.rows_.push_back(Row{line_number, std::move(fields)});
  }
  if (table.header_.empty()) return InvalidArgument(path + ": empty file, no header line");
  return table;
}

StatusOr<int> CsvTable::Column(const std::string& name) const {
  for (size_t i = 0; i < header_.size(); ++i) {
    if (header_[i] == name) return static_cast<int>(i);
  }
  return InvalidArgument(path_ + ": no column named " + name);
}

StatusOr<double> CsvTable::Number(size_t row, int column) const {
  const std::string& text = rows_[row].fields[column];
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end) {
    return InvalidArgument(path_ + ":" + std::to_string(rows_[row].line) + ": column " + header_[column] + " is \"" +
                           text + "\", not a number");
  }
  return value;
}

void AppendNumber(double value, std::string* out) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, 10);
  out->append(buffer, result.ptr);
}

void AppendField(double value, std::string* line) {
  line->push_back(',');
  if (!std::isnan(value)) AppendNumber(value, line);
}

}  // namespace localizer::io
