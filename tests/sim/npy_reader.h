// A tiny reader for 2-D float64 NumPy .npy files (format versions 1.0-3.0), for tests that
// compare with reference tables shipped as .npy.
//
// Layout: the 6-byte magic "\x93NUMPY", major and minor version bytes, the header length
// (little-endian uint16 for version 1, uint32 for 2 and 3), an ASCII Python-dict header
//     {'descr': '<f8', 'fortran_order': False, 'shape': (R, C), }
// padded with spaces and a newline, then R x C little-endian doubles, row-major (C order) or
// column-major when fortran_order is True. Anything else ('>f8', other dtypes, other ranks,
// a short or long payload) is an error, never a crash: ReadNpyMatrix returns NOT_FOUND when
// the file cannot be opened and INVALID_ARGUMENT naming the problem when it is malformed.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "engine/core/status.h"

namespace localizer::engine::testing {

struct NpyMatrix {
  int64_t rows = 0;
  int64_t cols = 0;
  bool fortran_order = false;
  std::vector<double> data;  // in file order

  double at(int64_t row, int64_t col) const { return fortran_order ? data[col * rows + row] : data[row * cols + col]; }
};

namespace npy_internal {

// The text after `'key':` (skipping spaces), or npos.
inline size_t ValueAfter(const std::string& header, const std::string& key) {
  const size_t k = header.find("'" + key + "'");
  if (k == std::string::npos) return k;
  size_t p = header.find(':', k);
  if (p == std::string::npos) return p;
  ++p;
  while (p < header.size() && header[p] == ' ') ++p;
  return p;
}

// Parses a non-negative decimal integer at `p`, advancing it; false if there is none.
inline bool ParseCount(const std::string& s, size_t& p, int64_t& value) {
  while (p < s.size() && s[p] == ' ') ++p;
  const size_t start = p;
  value = 0;
  while (p < s.size() && s[p] >= '0' && s[p] <= '9') {
    if (value > (int64_t{1} << 40)) return false;  // absurd size
    value = value * 10 + (s[p] - '0');
    ++p;
  }
  while (p < s.size() && s[p] == ' ') ++p;
  return p > start;
}

}  // namespace npy_internal

inline StatusOr<NpyMatrix> ReadNpyMatrix(const std::string& path) {
  static_assert(std::endian::native == std::endian::little, "reader assumes a little-endian host");
  std::ifstream file(path, std::ios::binary);
  if (!file) return NotFound(path + ": cannot open");
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::string where = path + ": ";
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) {
    return InvalidArgument(where + "not a .npy file (no \\x93NUMPY magic)");
  }
  const auto byte = [&](size_t i) { return static_cast<uint32_t>(static_cast<uint8_t>(bytes[i])); };
  const uint32_t major = byte(6);
  size_t header_start = 0;
  uint32_t header_len = 0;
  if (major == 1) {
    header_start = 10;
    header_len = byte(8) | byte(9) << 8;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) return InvalidArgument(where + "truncated preamble");
    header_start = 12;
    header_len = byte(8) | byte(9) << 8 | byte(10) << 16 | byte(11) << 24;
  } else {
    return InvalidArgument(where + "unsupported .npy version " + std::to_string(major));
  }
  if (header_start + header_len > bytes.size()) return InvalidArgument(where + "truncated header");
  const std::string header = bytes.substr(header_start, header_len);

  size_t p = npy_internal::ValueAfter(header, "descr");
  if (p == std::string::npos || header.compare(p, 5, "'<f8'") != 0) {
    return InvalidArgument(where + "descr is not '<f8' (little-endian float64): " + header);
  }
  NpyMatrix m;
  p = npy_internal::ValueAfter(header, "fortran_order");
  if (p != std::string::npos && header.compare(p, 4, "True") == 0) {
    m.fortran_order = true;
  } else if (p == std::string::npos || header.compare(p, 5, "False") != 0) {
    return InvalidArgument(where + "fortran_order is missing or not True/False: " + header);
  }
  p = npy_internal::ValueAfter(header, "shape");
  if (p == std::string::npos || header[p] != '(') {
    return InvalidArgument(where + "shape is missing: " + header);
  }
  ++p;
  if (!npy_internal::ParseCount(header, p, m.rows) || p >= header.size() || header[p] != ',' ||
      !npy_internal::ParseCount(header, ++p, m.cols) || p >= header.size() || header[p] != ')') {
    return InvalidArgument(where + "shape is not a 2-tuple (R, C): " + header);
  }
  const size_t payload = bytes.size() - header_start - header_len;
  if (m.cols > 0 && m.rows > static_cast<int64_t>(payload / sizeof(double)) / m.cols) {
    return InvalidArgument(where + "shape (" + std::to_string(m.rows) + ", " + std::to_string(m.cols) +
                           ") is larger than the file");
  }
  const auto count = static_cast<size_t>(m.rows * m.cols);
  if (payload != count * sizeof(double)) {
    return InvalidArgument(where + "payload is " + std::to_string(payload) + " bytes, the shape needs " +
                           std::to_string(count * sizeof(double)));
  }
  m.data.resize(count);
  if (count > 0) std::memcpy(m.data.data(), bytes.data() + header_start + header_len, payload);
  return m;
}

}  // namespace localizer::engine::testing
