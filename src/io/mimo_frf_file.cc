// FRF matrices from CSV tables, and the extension dispatch (mimo_frf_file.h).
#include "ctid/io/mimo_frf_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <complex>
#include <numbers>
#include <string_view>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/io/uff58.h"

namespace ctid::io {

namespace {

bool ends_with(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

int frf_channel_position(std::vector<std::string>& names, const std::string& name) {
  const auto at = std::find(names.begin(), names.end(), name);
  if (at != names.end()) return static_cast<int>(at - names.begin());
  names.push_back(name);
  return static_cast<int>(names.size()) - 1;
}

}  // namespace

MimoFrf mimo_frf_from_table(const CsvTable& table) {
  const std::string& source = table.source;
  MimoFrf frf;
  if (table.has_column("frequency")) {
    frf.frequencies = table.column("frequency");
  } else {
    require(table.has_column("frequency_hz"), source,
            ": no frequency column; an FRF matrix table needs \"frequency\" (rad/s) or "
            "\"frequency_hz\" (Hz)");
    frf.frequencies = 2.0 * std::numbers::pi * table.column("frequency_hz");
  }
  const Eigen::Index lines = frf.frequencies.size();
  require(lines > 0, source, ": the table has no rows");
  for (Eigen::Index l = 0; l < lines; ++l) {
    require(frf.frequencies(l) >= 0.0, source, ": row ", l + 1, ": frequency ", frf.frequencies(l),
            " is negative");
    require(l == 0 || frf.frequencies(l) > frf.frequencies(l - 1), source, ": row ", l + 1,
            ": frequency ", frf.frequencies(l), " does not exceed the row before's (",
            l > 0 ? frf.frequencies(l - 1) : 0.0, "); the frequencies must increase");
  }
  // The pairs, from the _real columns, in the order they appear.
  std::vector<std::pair<int, int>> pairs;
  std::vector<std::string> pair_names;
  for (const std::string& name : table.names) {
    if (!ends_with(name, "_real")) continue;
    const std::string pair = name.substr(0, name.size() - 5);
    const std::size_t slash = pair.rfind('/');
    require(slash != std::string::npos && slash > 0 && slash + 1 < pair.size(), source,
            ": column '", name, "' is not named <output>/<input>_real");
    require(table.has_column(pair + "_imag"), source, ": column '", name, "' has no partner '",
            pair, "_imag'");
    pairs.emplace_back(frf_channel_position(frf.output_names, pair.substr(0, slash)),
                       frf_channel_position(frf.input_names, pair.substr(slash + 1)));
    pair_names.push_back(pair);
  }
  for (const std::string& name : table.names) {
    if (ends_with(name, "_imag")) {
      require(table.has_column(name.substr(0, name.size() - 5) + "_real"), source, ": column '",
              name, "' has no partner '", name.substr(0, name.size() - 5), "_real'");
    }
  }
  require(!pairs.empty(), source,
          ": no FRF columns; an FRF matrix table names each entry's columns "
          "<output>/<input>_real and <output>/<input>_imag");
  const int n_y = frf.output_count();
  const int n_u = frf.input_count();
  std::vector<std::vector<int>> seen(static_cast<size_t>(n_y), std::vector<int>(n_u, -1));
  for (size_t c = 0; c < pairs.size(); ++c) {
    seen[static_cast<size_t>(pairs[c].first)][static_cast<size_t>(pairs[c].second)] =
        static_cast<int>(c);
  }
  for (int j = 0; j < n_y; ++j) {
    for (int k = 0; k < n_u; ++k) {
      require(seen[static_cast<size_t>(j)][static_cast<size_t>(k)] >= 0, source, ": entry ",
              frf.output_names[static_cast<size_t>(j)], "/",
              frf.input_names[static_cast<size_t>(k)], " of the ", n_y, " x ", n_u,
              " FRF matrix is missing (no column '", frf.output_names[static_cast<size_t>(j)], "/",
              frf.input_names[static_cast<size_t>(k)], "_real')");
    }
  }
  int variances = 0;
  for (const std::string& pair : pair_names) variances += table.has_column(pair + "_variance");
  require(variances == 0 || variances == static_cast<int>(pair_names.size()), source, ": ",
          variances, " of the ", pair_names.size(),
          " entries have a _variance column; give it for all or none");
  frf.response.assign(static_cast<size_t>(lines), Eigen::MatrixXcd(n_y, n_u));
  if (variances > 0) frf.variance.assign(static_cast<size_t>(lines), Eigen::MatrixXd(n_y, n_u));
  for (size_t c = 0; c < pairs.size(); ++c) {
    const auto [j, k] = pairs[c];
    const Eigen::VectorXd& re = table.column(pair_names[c] + "_real");
    const Eigen::VectorXd& im = table.column(pair_names[c] + "_imag");
    for (Eigen::Index l = 0; l < lines; ++l) {
      frf.response[static_cast<size_t>(l)](j, k) = {re(l), im(l)};
      if (variances > 0) {
        frf.variance[static_cast<size_t>(l)](j, k) = table.column(pair_names[c] + "_variance")(l);
      }
    }
  }
  bool coherence = true;
  for (const std::string& y : frf.output_names) coherence &= table.has_column("coherence_" + y);
  if (coherence) {
    frf.coherence.resize(lines, n_y);
    for (int j = 0; j < n_y; ++j) {
      frf.coherence.col(j) = table.column("coherence_" + frf.output_names[static_cast<size_t>(j)]);
    }
  }
  bool levels = true;
  for (const std::string& u : frf.input_names) levels &= table.has_column("input_level_" + u);
  if (levels) {
    frf.input_level.resize(lines, n_u);
    for (int k = 0; k < n_u; ++k) {
      frf.input_level.col(k) =
          table.column("input_level_" + frf.input_names[static_cast<size_t>(k)]);
    }
  }
  if (table.has_column("input_condition")) frf.input_condition = table.column("input_condition");
  return frf;
}

MimoFrf read_mimo_frf_csv(const std::filesystem::path& path) {
  return mimo_frf_from_table(read_csv(path));
}

CsvTable mimo_frf_table(const MimoFrf& frf) {
  const Eigen::Index n = frf.frequencies.size();
  CsvTable table;
  table.add_column("frequency", frf.frequencies);
  table.add_column("frequency_hz", frf.frequencies / (2.0 * std::numbers::pi));
  if (frf.input_condition.size() == n) table.add_column("input_condition", frf.input_condition);
  if (frf.input_level.rows() == n && frf.input_level.cols() == frf.input_count()) {
    for (int i = 0; i < frf.input_count(); ++i) {
      table.add_column("input_level_" + frf.input_names[static_cast<size_t>(i)],
                       frf.input_level.col(i));
    }
  }
  if (frf.coherence.rows() == n && frf.coherence.cols() == frf.output_count()) {
    for (int j = 0; j < frf.output_count(); ++j) {
      table.add_column("coherence_" + frf.output_names[static_cast<size_t>(j)],
                       frf.coherence.col(j));
    }
  }
  const bool variance = static_cast<Eigen::Index>(frf.variance.size()) == n;
  for (int j = 0; j < frf.output_count(); ++j) {
    for (int i = 0; i < frf.input_count(); ++i) {
      Eigen::VectorXd re(n), im(n), var(n);
      for (Eigen::Index l = 0; l < n; ++l) {
        const auto q = static_cast<size_t>(l);
        re(l) = frf.response[q](j, i).real();
        im(l) = frf.response[q](j, i).imag();
        if (variance) var(l) = frf.variance[q](j, i);
      }
      const std::string pair =
          frf.output_names[static_cast<size_t>(j)] + "/" + frf.input_names[static_cast<size_t>(i)];
      table.add_column(pair + "_real", re);
      table.add_column(pair + "_imag", im);
      if (variance) table.add_column(pair + "_variance", var);
    }
  }
  return table;
}

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace

bool is_universal_file_path(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".uff" || extension == ".unv" || extension == ".uf";
}

MimoFrf read_mimo_frf(const std::filesystem::path& path) {
  if (is_universal_file_path(path)) return read_uff58(path);
  if (lower_extension(path) == ".json") return mimo_frf_from_json(read_json(path), path.string());
  return read_mimo_frf_csv(path);
}

}  // namespace ctid::io
