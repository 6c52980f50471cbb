#include "data_flags.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <type_traits>
#include <utility>
#include <variant>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/mimo_preprocessing.h"
#include "ctid/io/csv.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/model_json.h"
#include "ctid/io/npy.h"
#include "ctid/io/sampled_data_csv.h"
#include "field_flags.h"

namespace ctid::cli {
namespace {

std::string column_list(const io::CsvTable& table) {
  std::string list;
  for (const std::string& name : table.names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

// "A:B", "A:" or ":B" into its two ends; empty ends stay empty.
std::pair<std::string, std::string> split_range(const std::string& flag, const std::string& text) {
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos || text == ":") {
    usage_error(flag + " '" + text + "': expected A:B (either end may be left out)");
  }
  return {text.substr(0, colon), text.substr(colon + 1)};
}

template <class T>
std::optional<T> parse_end(const std::string& flag, const std::string& range,
                           const std::string& text) {
  if (text.empty()) return std::nullopt;
  const std::optional<T> value = parse_number<T>(text);
  if (!value || (std::is_integral_v<T> && *value < 0)) {
    usage_error(flag + " '" + range + "': '" + text + "' is not a " +
                (std::is_integral_v<T> ? "row number (>= 0)" : "time in seconds"));
  }
  return value;
}

std::optional<Hold> parse_hold(const std::string& text) {
  if (text.empty()) return std::nullopt;
  if (text == "zoh") return Hold::zero_order_hold;
  if (text == "foh") return Hold::first_order_hold;
  usage_error("--input-hold '" + text + "': expected zoh or foh");
}

const char* hold_flag_name(Hold hold) { return hold == Hold::zero_order_hold ? "zoh" : "foh"; }

// The input hold: --input-hold, else the file's '# input_hold:' declaration, else zoh; a flag
// that contradicts the declaration is a usage error naming both.
Hold resolved_hold(const io::CsvTable& table, const std::string& path, const std::string& flag) {
  const std::optional<Hold> declared = io::declared_input_hold(table);
  const std::optional<Hold> flagged = parse_hold(flag);
  if (declared && flagged && *declared != *flagged) {
    usage_error(internal::concat("--input-hold ", flag, " contradicts ", path, ":",
                                 table.declaration("input_hold")->line,
                                 ", which declares input_hold: ", hold_flag_name(*declared)));
  }
  return flagged.value_or(declared.value_or(Hold::zero_order_hold));
}

}  // namespace

bool same_sample_time(double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); }

void read_controller(const std::string& path, std::optional<DiscreteTransferFunction>& digital,
                     std::optional<TransferFunction>& analog) {
  io::ControllerModel c = io::read_controller(path);
  if (auto* d = std::get_if<DiscreteTransferFunction>(&c)) {
    digital = std::move(*d);
  } else {
    analog = std::get<TransferFunction>(std::move(c));
  }
}

void add_two_stage_flags(CLI::App& app, bool& asked, TwoStageOptions& options,
                         const std::string& flag, const std::string& path, const std::string& group,
                         const std::string& description) {
  app.add_flag(flag, asked, description)->excludes("--controller")->group(group);
  FieldFlagSettings settings;
  settings.group = group;
  settings.needs = flag;
  settings.path = path;
  add_field_flags(app, options, settings);
}

void DataFlags::add_to(CLI::App& app, const std::string& name, bool with_reference, bool several) {
  if (several) {
    app.add_option(name, files,
                   "CSV data file(s) with a header row of column names, or .npy arrays "
                   "(columns 0, 1, ...); several files are records of one system fitted "
                   "together")
        ->required()
        ->check(CLI::ExistingFile);
  } else {
    app.add_option(name, file,
                   "CSV data file with a header row of column names, or a .npy array (columns "
                   "0, 1, ...)")
        ->required()
        ->check(CLI::ExistingFile);
  }
  app.add_option("--input-column", input_column, "Column holding the input u")
      ->capture_default_str()
      ->group("Data");
  app.add_option("--output-column", output_column, "Column holding the output y")
      ->capture_default_str()
      ->group("Data");
  if (with_reference) {
    app.add_option("--reference-column", reference_column,
                   "Column holding the reference r (closed loop only; default r)")
        ->group("Data");
  }
  app.add_option("--time-column", time_column, "Time column; its uniform step is the sample time")
      ->capture_default_str()
      ->group("Data");
  app.add_option("--time-unit", time_unit,
                 "Unit of the time column's stamps: s, ms or us (they are converted to seconds)")
      ->check(CLI::IsMember({"s", "ms", "us"}))
      ->capture_default_str()
      ->group("Data");
  app.add_option("--sample-time,-T", sample_time,
                 "Sample time h in seconds; overrides a time column (its first stamp stays the "
                 "start time)")
      ->check(positive_number())
      ->group("Data");
  app.add_option("--resample", resample,
                 "Irregular time stamps: move the record onto a uniform grid of this step "
                 "(seconds) from the first stamp, the input as it is held, the output linearly")
      ->check(positive_number())
      ->group("Data");
  app.add_option("--input-hold", input_hold,
                 "How u is continued between samples: zoh or foh (default: the file's "
                 "'# input_hold:' declaration, else zoh)")
      ->group("Data");
  add_preprocessing_to(app, true);
}

void DataFlags::add_preprocessing_to(CLI::App& app, bool with_input_scale) {
  app.add_option("--rows", rows, "Keep data rows A to B-1 (0-based, A:B, either end optional)")
      ->group("Preprocessing");
  app.add_option("--time", time, "Keep samples with A <= t < B seconds (A:B)")
      ->group("Preprocessing");
  if (detrend_fit) {
    app.add_option("--detrend", detrend,
                   "Remove nothing, the means, straight lines, or the trend the fit's record "
                   "had removed (fit)")
        ->check(CLI::IsMember({"none", "mean", "linear", "fit"}))
        ->capture_default_str()
        ->group("Preprocessing");
  } else {
    app.add_option("--detrend", detrend, "Remove nothing, the means, or straight lines")
        ->check(CLI::IsMember({"none", "mean", "linear"}))
        ->capture_default_str()
        ->group("Preprocessing");
  }
  app.add_option("--decimate", decimate,
                 "Keep every N-th sample after a zero-phase anti-alias lowpass filter")
      ->capture_default_str()
      ->group("Preprocessing");
  if (with_input_scale) {
    app.add_option("--scale-input", scale_input, "Multiply u by this factor")
        ->capture_default_str()
        ->group("Preprocessing");
  }
  app.add_option("--scale-output", scale_output,
                 with_input_scale ? "Multiply y (and r) by this factor"
                                  : "Multiply every output channel by this factor")
      ->capture_default_str()
      ->group("Preprocessing");
}

void DataFlags::stamps_in_seconds(io::CsvTable& table, const std::string& path) const {
  if (!table.has_column(time_column) || table.unreadable.count(time_column) > 0) return;
  Eigen::VectorXd& stamps = table.columns[static_cast<std::size_t>(
      std::find(table.names.begin(), table.names.end(), time_column) - table.names.begin())];
  if (time_unit == "ms") stamps *= 1e-3;
  if (time_unit == "us") stamps *= 1e-6;
  // A step of 1000 s or more is rare (daily records exist); said, not refused: stamps in
  // milliseconds read as seconds made h = 4000 s for a 4 s logger (issue 35).
  const Eigen::Index n = stamps.size();
  const double step = n > 1 ? (stamps(n - 1) - stamps(0)) / static_cast<double>(n - 1) : 0.0;
  if (time_unit == "s" && step >= 1000.0) {
    QueuedLine()
        << "note: the time column '" << time_column << "' of " << path << " steps by "
        << format_number(step)
        << " s; if its stamps are milliseconds or microseconds, pass --time-unit ms or us\n";
  }
}

bool DataFlags::preprocessing_asked(const CLI::App& app) const {
  for (const char* flag :
       {"--rows", "--time", "--detrend", "--decimate", "--scale-input", "--scale-output"}) {
    if (app.get_option_no_throw(flag) != nullptr && app.count(flag) > 0) return true;
  }
  return false;
}

SampledData DataFlags::load_file(const std::string& path, const CLI::App& app,
                                 bool need_reference) const {
  // The table lives only while the record is made from it, so a long record is not held
  // twice while it is preprocessed.
  Hold hold = Hold::zero_order_hold;
  SampledData record = [&] {
    io::CsvTable table = io::read_table(path);
    stamps_in_seconds(table, path);
    const bool reference_flag = app.get_option_no_throw("--reference-column") != nullptr &&
                                app.count("--reference-column") > 0;
    std::optional<Eigen::VectorXd> reference;
    std::string reference_name;
    if (need_reference) {
      reference_name = reference_column.empty() ? "r" : reference_column;
      if (!table.has_column(reference_name)) {
        usage_error(internal::concat("closed loop (--controller) needs the reference r, but ", path,
                                     " has no column '", reference_name, "' (columns: ",
                                     column_list(table), "); name it with --reference-column"));
      }
      reference = table.column(reference_name);
    } else if (reference_flag) {
      usage_error("--reference-column has no effect without --controller (open loop)");
    }
    const Eigen::VectorXd& u = table.column(input_column);
    const Eigen::VectorXd& y = table.column(output_column);
    const bool time_flag = app.count("--time-column") > 0;
    const bool h_flag = app.count("--sample-time") > 0;
    hold = resolved_hold(table, path, input_hold);
    const bool resample_flag = app.count("--resample") > 0;
    if (resample_flag && h_flag) usage_error("give --resample or --sample-time, not both");
    if (resample_flag && !table.has_column(time_column)) {
      usage_error(internal::concat(
          "--resample needs the time stamps, but ", path, " has no time column '", time_column,
          "' (columns: ", column_list(table), "); name it with --time-column"));
    }

    std::optional<SampledData> read;
    if (resample_flag) {
      const Eigen::VectorXd& stamps = table.column(time_column);
      try {
        read.emplace(ctid::resample(stamps, u, y, reference, resample, hold));
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(path + ": " + e.what());
      }
      QueuedLine() << "note: " << path << ": " << stamps.size()
                   << " time stamps resampled onto h = " << format_number(resample) << " s ("
                   << read->size() << " samples)\n";
    } else if (table.has_column(time_column)) {
      const Eigen::VectorXd& stamps = table.column(time_column);
      if (h_flag) {
        // -T wins; the stamps give the start time, and a disagreement is noted, not refused.
        try {
          const TimeStampCheck check = check_time_stamps(stamps);
          const double drift = std::abs(sample_time - check.step) * (stamps.size() - 1);
          if (check.worst_sample) {
            QueuedLine() << "note: the time column '" << time_column << "' of " << path
                         << " is not uniform (sample " << *check.worst_sample << " is "
                         << format_brief(check.deviation) << " s off its grid); --sample-time "
                         << format_number(sample_time) << " s is used\n";
          } else if (drift > check.tolerance) {
            QueuedLine() << "note: --sample-time " << format_number(sample_time)
                         << " s overrides the time column '" << time_column << "' of " << path
                         << " (step " << format_number(check.step) << " s)\n";
          }
        } catch (const InvalidArgument& e) {
          QueuedLine() << "note: the time column '" << time_column << "' of " << path << ": "
                       << e.what() << "; --sample-time " << format_number(sample_time)
                       << " s is used\n";
        }
        try {
          read.emplace(sample_time, u, y, reference, stamps(0));
        } catch (const InvalidArgument& e) {
          throw InvalidArgument(path + ": " + e.what());
        }
      } else {
        io::CsvColumns columns;
        columns.time = time_column;
        columns.input = input_column;
        columns.output = output_column;
        columns.reference = reference_name;
        try {
          read.emplace(io::sampled_data_from_table(table, columns));
        } catch (const InvalidArgument& e) {
          const std::string message = e.what();
          if (message.find("time stamps") == std::string::npos) {
            throw InvalidArgument(message.starts_with(path) ? message : path + ": " + message);
          }
          throw InvalidArgument(message +
                                "; --sample-time (-T) overrides the time column, and --resample H "
                                "moves irregular stamps onto a grid of step H");
        }
      }
    } else {
      if (time_flag) table.column(time_column);  // throws, naming the columns present
      if (!h_flag) {
        usage_error(internal::concat(path, " has no time column '", time_column,
                                     "'; give --sample-time (or --time-column)"));
      }
      try {
        read.emplace(sample_time, u, y, reference);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(path + ": " + e.what());
      }
    }

    return std::move(*read);
  }();

  const PreprocessingOptions options = preprocessing_options();
  PreprocessedData result = [&] {
    try {
      return preprocess(std::move(record).with_input_hold(hold), options);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(path + ": " + e.what());
    }
  }();
  for (const std::string& warning : result.record.warnings) {
    QueuedLine() << "warning: " << path << ": " << warning;
  }
  preprocessing = std::move(result.record);
  return std::move(result.data);
}

IrregularRecord DataFlags::load_irregular(const CLI::App& app) const {
  for (const char* flag :
       {"--resample", "--sample-time", "--rows", "--time", "--decimate", "--reference-column"}) {
    if (app.get_option_no_throw(flag) != nullptr && app.count(flag) > 0) {
      usage_error(std::string(flag) +
                  " does not go with --irregular, which takes the time stamps as logged "
                  "(docs/decisions/0034)");
    }
  }
  if (detrend == "linear") {
    usage_error("--detrend linear does not go with --irregular yet; use --detrend mean");
  }
  const std::string& path = files.empty() ? file : files.front();
  io::CsvTable table = io::read_table(path);
  stamps_in_seconds(table, path);
  if (!table.has_column(time_column)) {
    usage_error(internal::concat(
        "--irregular needs the time stamps, but ", path, " has no time column '", time_column,
        "' (columns: ", column_list(table), "); name it with --time-column"));
  }
  IrregularRecord r;
  r.time = table.column(time_column);
  r.input = table.column(input_column) * scale_input;
  r.output = table.column(output_column) * scale_output;
  r.input_hold = resolved_hold(table, path, input_hold);
  try {
    r.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(path + ": " + e.what() + " (time column '" + time_column + "')");
  }
  if (detrend == "mean") {
    r.input.array() -= r.input.mean();
    r.output.array() -= r.output.mean();
  }
  return r;
}

void DataFlags::add_mimo_columns(CLI::App& app) {
  app.add_option("--input-columns", input_columns,
                 "Several inputs: columns or ranges A:B (file order), comma-separated, e.g. "
                 "u1,u2 or u1:u2")
      ->delimiter(',')
      ->group("Data");
  app.add_option("--output-columns", output_columns,
                 "Several outputs: columns or ranges A:B (file order), comma-separated, e.g. "
                 "y1:y28")
      ->delimiter(',')
      ->group("Data");
}

bool DataFlags::mimo_asked(const CLI::App& app) const {
  return app.count("--input-columns") > 0 || app.count("--output-columns") > 0;
}

PreprocessingOptions DataFlags::preprocessing_options() const {
  PreprocessingOptions options;
  if (!rows.empty() && !time.empty()) usage_error("give --rows or --time, not both");
  if (!rows.empty()) {
    const auto [a, b] = split_range("--rows", rows);
    options.first_row = parse_end<int>("--rows", rows, a);
    options.end_row = parse_end<int>("--rows", rows, b);
  }
  if (!time.empty()) {
    const auto [a, b] = split_range("--time", time);
    options.start_time = parse_end<double>("--time", time, a);
    options.end_time = parse_end<double>("--time", time, b);
  }
  if (decimate < 1) usage_error(internal::concat("--decimate is ", decimate, "; it must be >= 1"));
  if (!(scale_input > 0.0) || !(scale_output > 0.0)) {
    usage_error("--scale-input and --scale-output must be > 0");
  }
  // --detrend fit: loaded as measured; the command removes the fit's trend afterwards.
  options.detrend = detrend == "fit" ? Detrend::none : *enum_from_name<Detrend>(detrend);
  options.decimate = decimate;
  options.input_scale = scale_input;
  options.output_scale = scale_output;
  return options;
}

MimoData DataFlags::load_mimo(const CLI::App& app) const {
  if (app.count("--input-columns") > 0 && app.count("--input-column") > 0) {
    usage_error("give --input-column or --input-columns, not both");
  }
  if (app.count("--output-columns") > 0 && app.count("--output-column") > 0) {
    usage_error("give --output-column or --output-columns, not both");
  }
  for (const char* flag : {"--resample", "--reference-column"}) {
    if (app.get_option_no_throw(flag) != nullptr && app.count(flag) > 0) {
      usage_error(std::string(flag) +
                  " is not available with --input-columns / --output-columns yet");
    }
  }
  if (files.size() > 1) usage_error("several inputs/outputs take one data file");
  // DATA lands in `files` when the command takes several (ctid fit), else in `file`.
  io::CsvTable table = io::read_table(files.empty() ? file : files.front());
  stamps_in_seconds(table, files.empty() ? file : files.front());
  io::MimoCsvColumns columns;
  columns.time = time_column;
  columns.inputs = input_columns.empty() ? std::vector<std::string>{input_column} : input_columns;
  columns.outputs =
      output_columns.empty() ? std::vector<std::string>{output_column} : output_columns;
  const bool h_flag = app.count("--sample-time") > 0;
  std::optional<MimoData> read;
  if (table.has_column(time_column) && !h_flag) {
    try {
      read.emplace(io::mimo_data_from_table(table, columns));
    } catch (const InvalidArgument& e) {
      const std::string message = e.what();
      if (message.find("time stamps") == std::string::npos) throw;
      throw InvalidArgument(message + "; --sample-time (-T) overrides the time column");
    }
  } else {
    if (!h_flag) {
      if (app.count("--time-column") > 0) table.column(time_column);  // names the columns
      usage_error(internal::concat(file, " has no time column '", time_column,
                                   "'; give --sample-time (or --time-column)"));
    }
    // The columns by the same rules, the time column left out (it may be absent).
    io::CsvTable untimed = table;
    untimed.names.clear();
    untimed.columns.clear();
    for (std::size_t c = 0; c < table.names.size(); ++c) {
      if (table.names[c] != time_column) untimed.add_column(table.names[c], table.columns[c]);
    }
    const double start = table.has_column(time_column) ? table.column(time_column)(0) : 0.0;
    untimed.add_column(
        time_column,
        Eigen::VectorXd::LinSpaced(table.rows(), start, start + sample_time * (table.rows() - 1)));
    const MimoData m = io::mimo_data_from_table(untimed, columns);
    read.emplace(MimoData(sample_time, m.inputs(), m.outputs(), std::nullopt, start)
                     .with_names(m.input_names(), m.output_names())
                     .with_input_hold(m.input_hold()));
  }
  const std::optional<Hold> declared = io::declared_input_hold(table);
  const std::optional<Hold> flagged = parse_hold(input_hold);
  if (declared && flagged && *declared != *flagged) {
    usage_error(internal::concat("--input-hold ", input_hold, " contradicts ", file, ":",
                                 table.declaration("input_hold")->line,
                                 ", which declares input_hold: ", hold_flag_name(*declared)));
  }
  if (flagged) read.emplace(read->with_input_hold(*flagged));
  PreprocessedMimoData result = [&] {
    try {
      return preprocess(*read, preprocessing_options());
    } catch (const InvalidArgument& e) {
      throw InvalidArgument((files.empty() ? file : files.front()) + ": " + e.what());
    }
  }();
  for (const std::string& warning : result.record.warnings) {
    QueuedLine() << "warning: " << (files.empty() ? file : files.front()) << ": " << warning
                 << "\n";
  }
  preprocessing = std::move(result.record);
  return std::move(result.data);
}

SampledData DataFlags::load(const CLI::App& app, bool need_reference) const {
  return load_file(file, app, need_reference);
}

std::vector<SampledData> DataFlags::load_all(const CLI::App& app, bool need_reference) const {
  std::vector<SampledData> records;
  for (const std::string& path : files.empty() ? std::vector<std::string>{file} : files) {
    records.push_back(load_file(path, app, need_reference));
  }
  return records;
}

std::string DataFlags::file_list() const {
  if (files.empty()) return file;
  std::string text;
  for (const std::string& path : files) text += (text.empty() ? "" : ", ") + path;
  return text;
}

}  // namespace ctid::cli
