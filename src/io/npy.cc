#include "ctid/io/npy.h"

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/io/file.h"
#include "io/internal/echo.h"

namespace ctid::io {
namespace {

// The header is a Python dict literal such as
//   {'descr': '<f8', 'fortran_order': False, 'shape': (100000, 3), }
// read by a small scanner over exactly the forms NumPy writes (quoted strings, True/False,
// tuples of integers).
class HeaderScanner {
 public:
  HeaderScanner(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  void skip_space() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  }
  bool accept(char c) {
    skip_space();
    if (at_ < text_.size() && text_[at_] == c) {
      ++at_;
      return true;
    }
    return false;
  }
  void expect(char c, const char* what) {
    if (!accept(c)) fail(ctid::internal::concat("expected ", what));
  }
  std::string quoted() {
    skip_space();
    if (at_ >= text_.size() || (text_[at_] != '\'' && text_[at_] != '"')) {
      fail("expected a quoted string");
    }
    const char quote = text_[at_++];
    const size_t close = text_.find(quote, at_);
    if (close == std::string_view::npos) fail("a string is not closed");
    std::string value(text_.substr(at_, close - at_));
    at_ = close + 1;
    return value;
  }
  bool boolean() {
    skip_space();
    for (const auto& [word, value] : {std::pair{"True", true}, std::pair{"False", false}}) {
      const size_t length = std::strlen(word);
      if (text_.substr(at_, length) == word) {
        at_ += length;
        return value;
      }
    }
    fail("fortran_order is neither True nor False");
  }
  std::vector<std::uint64_t> shape() {
    expect('(', "'(' opening the shape");
    std::vector<std::uint64_t> axes;
    while (!accept(')')) {
      skip_space();
      std::uint64_t n = 0;
      size_t digits = 0;
      while (at_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[at_]))) {
        if (n > (UINT64_MAX - 9) / 10) fail("an axis length is too large");
        n = n * 10 + static_cast<std::uint64_t>(text_[at_++] - '0');
        ++digits;
      }
      if (digits == 0) fail("the shape must be a tuple of non-negative integers");
      axes.push_back(n);
      if (!accept(',')) {
        expect(')', "')' closing the shape");
        break;
      }
    }
    return axes;
  }
  // Skips a value of a key ctid does not know (NumPy writes none, but a later version may).
  void skip_value() {
    skip_space();
    if (at_ < text_.size() && (text_[at_] == '\'' || text_[at_] == '"')) {
      quoted();
      return;
    }
    int depth = 0;
    while (at_ < text_.size()) {
      const char c = text_[at_];
      if (c == '(' || c == '[' || c == '{') ++depth;
      if ((c == ')' || c == ']' || c == '}') && depth-- == 0) return;
      if (c == ',' && depth == 0) return;
      ++at_;
    }
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidArgument(ctid::internal::concat(source_, ": malformed .npy header (", what, "): '",
                                                 internal::echo(text_), "'"));
  }

 private:
  std::string_view text_;
  const std::string& source_;
  size_t at_ = 0;
};

struct Header {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::uint64_t> shape;
};

Header parse_header(std::string_view text, const std::string& source) {
  // Trailing padding (spaces and a newline) is not part of the dict.
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) {
    text.remove_suffix(1);
  }
  HeaderScanner scan(text, source);
  Header header;
  bool has_descr = false;
  bool has_order = false;
  bool has_shape = false;
  std::set<std::string> keys;
  scan.expect('{', "'{' opening the header dict");
  while (!scan.accept('}')) {
    const std::string key = scan.quoted();
    if (!keys.insert(key).second) scan.fail("the key '" + internal::echo(key) + "' appears twice");
    scan.expect(':', "':' after a key");
    if (key == "descr") {
      scan.skip_space();
      if (scan.accept('[')) {
        throw InvalidArgument(ctid::internal::concat(
            source,
            ": the array has a structured dtype (named fields); ctid reads plain "
            "numeric arrays: save a 2-D float64 array of samples x columns"));
      }
      header.descr = scan.quoted();
      has_descr = true;
    } else if (key == "fortran_order") {
      header.fortran_order = scan.boolean();
      has_order = true;
    } else if (key == "shape") {
      header.shape = scan.shape();
      has_shape = true;
    } else {
      scan.skip_value();
    }
    if (!scan.accept(',')) {
      scan.expect('}', "'}' closing the header dict");
      break;
    }
  }
  if (!has_descr) scan.fail("no 'descr'");
  if (!has_order) scan.fail("no 'fortran_order'");
  if (!has_shape) scan.fail("no 'shape'");
  return header;
}

enum class Kind { floating, signed_integer, unsigned_integer };

struct Dtype {
  Kind kind = Kind::floating;
  size_t size = 8;
};

Dtype parse_dtype(const std::string& descr, const std::string& source) {
  const auto unsupported = [&](const std::string& why) {
    return InvalidArgument(
        ctid::internal::concat(source, ": dtype '", descr, "' is not supported (", why,
                               "); ctid reads little-endian float64, float32 and "
                               "integer arrays: save a.astype('<f8')"));
  };
  if (descr.size() < 3) throw unsupported("not a numeric type");
  const char order = descr[0];
  const char kind = descr[1];
  const std::string size_text = descr.substr(2);
  if (order == '>') throw unsupported("big-endian");
  if (order != '<' && order != '|' && order != '=') throw unsupported("not a numeric type");
  size_t size = 0;
  for (const char c : size_text) {
    if (!std::isdigit(static_cast<unsigned char>(c)) || size > 100) {
      throw unsupported("not a numeric type");
    }
    size = size * 10 + static_cast<size_t>(c - '0');
  }
  if (kind == 'f' && (size == 4 || size == 8)) return {Kind::floating, size};
  if (kind == 'i' && (size == 1 || size == 2 || size == 4 || size == 8)) {
    return {Kind::signed_integer, size};
  }
  if (kind == 'u' && (size == 1 || size == 2 || size == 4 || size == 8)) {
    return {Kind::unsigned_integer, size};
  }
  if (kind == 'f') throw unsupported("only 4- and 8-byte floats");
  if (kind == 'c') throw unsupported("complex");
  if (kind == 'b') throw unsupported("bool");
  if (kind == 'O') throw unsupported("Python objects");
  if (kind == 'U' || kind == 'S' || kind == 'a') throw unsupported("strings");
  throw unsupported("not a numeric type");
}

// Little-endian bytes as an unsigned integer of `size` bytes, whatever the host order.
std::uint64_t little_endian(const unsigned char* p, size_t size) {
  std::uint64_t value = 0;
  for (size_t i = size; i-- > 0;) value = (value << 8) | p[i];
  return value;
}

double element(const unsigned char* p, const Dtype& dtype) {
  const std::uint64_t bits = little_endian(p, dtype.size);
  switch (dtype.kind) {
    case Kind::floating:
      if (dtype.size == 8) {
        double value = 0.0;
        std::memcpy(&value, &bits, sizeof value);
        return value;
      } else {
        const auto narrow = static_cast<std::uint32_t>(bits);
        float value = 0.0F;
        std::memcpy(&value, &narrow, sizeof value);
        return static_cast<double>(value);
      }
    case Kind::signed_integer: {
      // Sign-extend from the element's width.
      const unsigned shift = static_cast<unsigned>(64 - 8 * dtype.size);
      return static_cast<double>(static_cast<std::int64_t>(bits << shift) >> shift);
    }
    case Kind::unsigned_integer:
      return static_cast<double>(bits);
  }
  return 0.0;
}

}  // namespace

namespace {

// What the preamble and header say, checked against the number of bytes that follow.
struct Layout {
  std::string descr;
  int dimensions = 2;
  Dtype dtype;
  std::uint64_t rows = 0;
  std::uint64_t columns = 0;
  const unsigned char* data = nullptr;  // the first element
};

Layout layout_of(std::string_view bytes, const std::string& source) {
  constexpr std::string_view kMagic = "\x93NUMPY";
  require(bytes.substr(0, kMagic.size()) == kMagic, source,
          ": not a .npy file (it does not start with the magic string \\x93NUMPY)");
  require(bytes.size() >= 10, source, ": truncated .npy file (", bytes.size(),
          " bytes, shorter than the preamble)");
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const int major = data[6];
  const int minor = data[7];
  require(major >= 1 && major <= 3, source, ": .npy format version ", major, ".", minor,
          " is not supported (ctid reads versions 1.0, 2.0 and 3.0)");
  const size_t length_bytes = major == 1 ? 2 : 4;
  require(bytes.size() >= 8 + length_bytes, source, ": truncated .npy file (", bytes.size(),
          " bytes, shorter than the preamble)");
  const size_t header_length = static_cast<size_t>(little_endian(data + 8, length_bytes));
  const size_t header_start = 8 + length_bytes;
  require(bytes.size() - header_start >= header_length, source,
          ": truncated .npy file (the header is ", header_length, " bytes but only ",
          bytes.size() - header_start, " follow the preamble)");
  const Header header = parse_header(bytes.substr(header_start, header_length), source);
  Layout layout;
  layout.dtype = parse_dtype(header.descr, source);
  require(!header.fortran_order || header.shape.size() < 2, source,
          ": the array is in Fortran order (column-major); ctid reads C order: save "
          "np.ascontiguousarray(a)");
  require(header.shape.size() == 1 || header.shape.size() == 2, source, ": the array has ",
          header.shape.size(),
          " axes; ctid reads a 1-D array (one signal) or a 2-D array of "
          "samples x columns");
  const std::uint64_t rows = header.shape[0];
  const std::uint64_t columns = header.shape.size() == 2 ? header.shape[1] : 1;
  require(rows > 0 && columns > 0, source, ": the array is empty (shape ", rows,
          header.shape.size() == 2 ? ctid::internal::concat(" x ", columns) : std::string(),
          "); it needs at least one sample and one column");
  // Limits that keep the sizes below from overflowing; far beyond any record in memory.
  require(rows < (std::uint64_t{1} << 40) && columns < (std::uint64_t{1} << 20) &&
              rows * columns < (std::uint64_t{1} << 40),
          source, ": the array's shape ", rows, " x ", columns, " is too large");
  const size_t data_start = header_start + header_length;
  const std::uint64_t expected = rows * columns * layout.dtype.size;
  const std::uint64_t present = bytes.size() - data_start;
  require(present >= expected, source, ": truncated .npy file (the shape ", rows, " x ", columns,
          " of ", header.descr, " needs ", expected, " data bytes but only ", present,
          " follow the header)");
  require(present == expected, source, ": ", present - expected,
          " bytes follow the array's data; the file is not one .npy array");
  layout.descr = header.descr;
  layout.dimensions = static_cast<int>(header.shape.size());
  layout.rows = rows;
  layout.columns = columns;
  layout.data = data + data_start;
  return layout;
}

// Calls set(row, column, value) for every element, in file (row-major) order, then checks
// that every value is finite (naming the first one that is not).
template <class Set>
void decode(const Layout& layout, const std::string& source, Set&& set) {
  const auto rows = static_cast<Eigen::Index>(layout.rows);
  const auto columns = static_cast<Eigen::Index>(layout.columns);
  const unsigned char* p = layout.data;
  const bool native = layout.dtype.kind == Kind::floating && layout.dtype.size == 8 &&
                      std::endian::native == std::endian::little;
  bool finite = true;
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < columns; ++c, p += layout.dtype.size) {
      double value = 0.0;
      if (native) {
        std::memcpy(&value, p, sizeof value);  // np.save of float64 on a little-endian host
      } else {
        value = element(p, layout.dtype);
      }
      finite = finite && std::isfinite(value);
      set(r, c, value);
    }
  }
  if (finite) return;
  p = layout.data;
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < columns; ++c, p += layout.dtype.size) {
      const double value = element(p, layout.dtype);
      require(std::isfinite(value), source, ": row ", r, " (0-based), column '", c, "': value ",
              value, " is not finite; every value must be a finite number");
    }
  }
}

}  // namespace

NpyArray parse_npy(std::string_view bytes, const std::string& source) {
  const Layout layout = layout_of(bytes, source);
  NpyArray array;
  array.dtype = layout.descr;
  array.dimensions = layout.dimensions;
  array.values.resize(static_cast<Eigen::Index>(layout.rows),
                      static_cast<Eigen::Index>(layout.columns));
  decode(layout, source,
         [&](Eigen::Index r, Eigen::Index c, double value) { array.values(r, c) = value; });
  return array;
}

CsvTable parse_npy_table(std::string_view bytes, const std::string& source) {
  const Layout layout = layout_of(bytes, source);
  CsvTable table;
  table.source = source;
  for (std::uint64_t c = 0; c < layout.columns; ++c) {
    table.names.push_back(std::to_string(c));
    table.columns.emplace_back(static_cast<Eigen::Index>(layout.rows));
  }
  decode(layout, source, [&](Eigen::Index r, Eigen::Index c, double value) {
    table.columns[static_cast<size_t>(c)](r) = value;
  });
  return table;
}

NpyArray read_npy(const std::filesystem::path& path) {
  return parse_npy(read_text_file(path), path.string());
}

CsvTable npy_table(const NpyArray& array, const std::string& source) {
  CsvTable table;
  table.source = source;
  for (Eigen::Index c = 0; c < array.values.cols(); ++c) {
    table.names.push_back(std::to_string(c));
    table.columns.emplace_back(array.values.col(c));
  }
  return table;
}

bool is_npy_path(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".npy";
}

CsvTable read_table(const std::filesystem::path& path) {
  if (is_npy_path(path)) return parse_npy_table(read_text_file(path), path.string());
  return read_csv(path);
}

}  // namespace ctid::io
