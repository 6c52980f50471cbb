#include "ctid/io/mimo_data_csv.h"

#include <algorithm>
#include <cstddef>
#include <map>
#include <optional>
#include <utility>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"
#include "ctid/io/npy.h"
#include "ctid/io/sampled_data_csv.h"

namespace ctid::io {
namespace {

std::string column_list(const CsvTable& table) {
  std::string list;
  for (const std::string& name : table.names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

std::size_t position(const CsvTable& table, const std::string& name, std::string_view role,
                     const std::string& entry) {
  const auto it = std::find(table.names.begin(), table.names.end(), name);
  if (it == table.names.end()) {
    const std::string in_range = entry == name ? "" : " (in range '" + entry + "')";
    throw InvalidArgument(ctid::internal::concat(table.source, ": ", role, " column '", name,
                                                 "' not found", in_range, "; columns are ",
                                                 column_list(table)));
  }
  return static_cast<std::size_t>(it - table.names.begin());
}

Eigen::MatrixXd gather(const CsvTable& table, const std::vector<std::string>& names) {
  Eigen::MatrixXd m(table.rows(), static_cast<Eigen::Index>(names.size()));
  for (std::size_t j = 0; j < names.size(); ++j) {
    m.col(static_cast<Eigen::Index>(j)) = table.column(names[j]);
  }
  return m;
}

}  // namespace

void MimoCsvColumns::check_relations(const std::string& path) const {
  require(!time.empty(), path, ".time is empty; it must name the time column");
  require(!inputs.empty(), path, ".inputs is empty; name at least one input column");
  require(!outputs.empty(), path, ".outputs is empty; name at least one output column");
  for (const auto* list : {&inputs, &outputs, &references}) {
    for (const std::string& entry : *list) {
      require(!entry.empty(), path, " has an empty column name");
    }
  }
}

std::vector<std::string> expand_columns(const CsvTable& table,
                                        const std::vector<std::string>& entries,
                                        std::string_view role) {
  std::vector<std::string> names;
  for (const std::string& entry : entries) {
    require(!entry.empty(), table.source, ": an empty ", role, " column name");
    const std::size_t colon = entry.find(':');
    // A column whose own name holds a colon is taken as it is, not as a range.
    if (colon == std::string::npos || table.has_column(entry)) {
      position(table, entry, role, entry);
      names.push_back(entry);
      continue;
    }
    const std::string first = entry.substr(0, colon);
    const std::string last = entry.substr(colon + 1);
    require(!first.empty() && !last.empty() && last.find(':') == std::string::npos, table.source,
            ": ", role, " range '", entry, "' must be A:B, two column names");
    const std::size_t a = position(table, first, role, entry);
    const std::size_t b = position(table, last, role, entry);
    require(a <= b, table.source, ": ", role, " range '", entry, "': column '", first,
            "' comes after '", last, "' in the file; write ", last, ":", first,
            " or name the columns one by one");
    for (std::size_t i = a; i <= b; ++i) names.push_back(table.names[i]);
  }
  return names;
}

MimoData mimo_data_from_table(const CsvTable& table, const MimoCsvColumns& columns) {
  columns.validate();
  position(table, columns.time, "time", columns.time);
  const std::vector<std::string> inputs = expand_columns(table, columns.inputs, "input");
  const std::vector<std::string> outputs = expand_columns(table, columns.outputs, "output");
  const std::vector<std::string> references =
      expand_columns(table, columns.references, "reference");
  // Every column stands for one signal only.
  std::map<std::string, std::string> role_of{{columns.time, "time"}};
  const auto claim = [&](const std::vector<std::string>& names, const std::string& role) {
    for (const std::string& name : names) {
      const auto [it, inserted] = role_of.emplace(name, role);
      require(inserted, table.source, ": column '", name, "' is named twice (as ", it->second,
              " and as ", role, "); each column can be one signal only");
    }
  };
  claim(inputs, "input");
  claim(outputs, "output");
  claim(references, "reference");
  require(references.empty() || references.size() == inputs.size(), table.source, ": ",
          references.size(), " reference column", references.size() == 1 ? "" : "s", " for ",
          inputs.size(), " input", inputs.size() == 1 ? "" : "s", "; give one reference per input");

  for (const std::vector<std::string>* names : {&inputs, &outputs, &references}) {
    for (const std::string& name : *names) {
      ctid::internal::require_magnitude_in_range(table.column(name),
                                                 table.source + ": column '" + name + "'");
    }
  }
  const Hold hold = declared_input_hold(table).value_or(Hold::zero_order_hold);
  const TimeGrid grid = uniform_time_grid(table, columns.time, columns.relative_tolerance);
  std::optional<Eigen::MatrixXd> reference_matrix;
  if (!references.empty()) reference_matrix = gather(table, references);
  try {
    return MimoData(grid.sample_time, gather(table, inputs), gather(table, outputs),
                    std::move(reference_matrix), grid.start_time)
        .with_names(inputs, outputs)
        .with_input_hold(hold);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(ctid::internal::concat(table.source, ": ", e.what()));
  }
}

MimoData read_mimo_data(const std::filesystem::path& path, const MimoCsvColumns& columns) {
  columns.validate();
  return mimo_data_from_table(read_table(path), columns);
}

CsvTable to_csv_table(const MimoData& data, const std::string& time_column) {
  CsvTable table;
  if (data.input_hold() != Hold::zero_order_hold) {
    table.declarations.push_back({"input_hold", "foh", 0});
  }
  table.add_column(time_column, data.time());
  for (int i = 0; i < data.input_count(); ++i) {
    table.add_column(data.input_names()[static_cast<std::size_t>(i)], data.inputs().col(i));
  }
  for (int j = 0; j < data.output_count(); ++j) {
    table.add_column(data.output_names()[static_cast<std::size_t>(j)], data.outputs().col(j));
  }
  if (data.has_references()) {
    for (int i = 0; i < data.input_count(); ++i) {
      table.add_column("r_" + data.input_names()[static_cast<std::size_t>(i)],
                       data.references().col(i));
    }
  }
  return table;
}

void write_mimo_data(const std::filesystem::path& path, const MimoData& data,
                     const std::string& time_column, Overwrite overwrite) {
  write_csv(path, to_csv_table(data, time_column), overwrite);
}

}  // namespace ctid::io
