// The data flags shared by the estimation commands (fit, validate, frf): which CSV columns
// hold u, y and r, where the sample time comes from (a uniform time column, or --sample-time,
// which overrides it), how the input is held (--input-hold or the file's declaration), and
// the preprocessing (core/preprocessing.h: --rows/--time, --detrend, --decimate, --scale-*).
// Errors are one line naming the file, the column and the flag to use.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ctid/core/mimo_data.h"
#include "ctid/core/preprocessing.h"
#include "ctid/core/sampled_data.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/two_stage.h"
#include "ctid/io/csv.h"

namespace ctid::cli {

struct DataFlags {
  std::string file;                ///< the data file (commands that take one)
  std::vector<std::string> files;  ///< the data files (commands that take several)
  std::string input_column = "u";
  std::string output_column = "y";
  std::string reference_column;  ///< empty: "r" when a reference is needed
  std::string time_column = "t";
  std::string time_unit = "s";  ///< unit of the time column: s, ms or us
  double sample_time = 0.0;
  double resample = 0.0;   ///< --resample H: irregular stamps onto a grid of step H
  std::string input_hold;  ///< "zoh" or "foh"; empty: the file's declaration, else zoh
  std::string rows;        ///< "A:B"; empty: all
  std::string time;        ///< "A:B" in seconds; empty: all
  std::string detrend = "none";
  /// --detrend also takes `fit` (ctid validate): the record is loaded without detrending and
  /// the command removes the fit's trend (core/preprocessing.h: remove_trend).
  bool detrend_fit = false;
  int decimate = 1;
  double scale_input = 1.0;
  double scale_output = 1.0;

  /// Several inputs / outputs (add_mimo_columns): names or ranges A:B of the file's columns.
  std::vector<std::string> input_columns;
  std::vector<std::string> output_columns;

  /// What load() did to the record (set by load(), which the commands call on const flags).
  mutable PreprocessingRecord preprocessing;

  /// Adds DATA (positional, `name` in the help) and the column flags to `app`; with
  /// `with_reference` also --reference-column.
  /// With `several`, DATA takes one or more files (into `files`, else into `file`).
  void add_to(CLI::App& app, const std::string& name, bool with_reference, bool several = false);
  /// Adds only the preprocessing flags (--rows, --time, --detrend, --decimate, --scale-*;
  /// --scale-input only `with_input_scale`): what add_to adds besides DATA and the columns.
  void add_preprocessing_to(CLI::App& app, bool with_input_scale);
  /// The preprocessing the flags ask for (usage errors for malformed ranges and factors).
  PreprocessingOptions preprocessing_options() const;

  /// Reads the record. With `need_reference` the reference column must be present (its
  /// absence is a usage error naming --reference-column); without it, --reference-column is
  /// a usage error. `app` tells which flags were given. Preprocesses the record as the flags
  /// ask, keeps the record of it in `preprocessing` and prints its warnings on stderr.
  SampledData load(const CLI::App& app, bool need_reference) const;
  /// Adds --input-columns and --output-columns (comma lists of names and ranges A:B).
  void add_mimo_columns(CLI::App& app);
  /// Whether --input-columns or --output-columns was given.
  bool mimo_asked(const CLI::App& app) const;
  /// Reads a record with the columns of --input-columns / --output-columns (the single
  /// --input-column / --output-column stands in for a list not given). The sample time comes
  /// from the time column or --sample-time; the preprocessing flags apply to every channel
  /// (core/mimo_preprocessing.h); --resample and --reference-column are usage errors.
  MimoData load_mimo(const CLI::App& app) const;

  /// Reads `file` as a record at irregular time stamps (fit and validate --irregular, decisions
  /// 0034 and 0053): the
  /// time column as logged (duplicates and gaps kept), u and y, the input hold from
  /// --input-hold or the file's declaration. Of the preprocessing only --detrend none|mean
  /// and --scale-input/--scale-output apply; --resample, --sample-time, --rows, --time,
  /// --decimate, --detrend linear and --reference-column are usage errors naming the flag.
  IrregularRecord load_irregular(const CLI::App& app) const;

  /// load() of every file, each read, checked and preprocessed alike.
  std::vector<SampledData> load_all(const CLI::App& app, bool need_reference) const;
  /// The files as the summary names them: "a.csv" or "a.csv, b.csv".
  std::string file_list() const;

  /// Whether any preprocessing flag was given (then commands print preprocessing.summary()).
  bool preprocessing_asked(const CLI::App& app) const;
  /// Converts the time column of `table` (if any) from --time-unit to seconds, and notes a
  /// step of 1000 s or more read in seconds (stamps that may be milliseconds).
  void stamps_in_seconds(io::CsvTable& table, const std::string& path) const;

 private:
  SampledData load_file(const std::string& path, const CLI::App& app, bool need_reference) const;
};

/// Agreement of two sample times given in different places (flag, file, controller).
bool same_sample_time(double a, double b);

/// The file of --controller: a discrete_transfer_function is a digital controller C_d(q), put
/// in `digital`; a transfer_function an analog one C(p), put in `analog` (decision 0067).
void read_controller(const std::string& path, std::optional<DiscreteTransferFunction>& digital,
                     std::optional<TransferFunction>& analog);

/// The flag `flag` (--two-stage: closed loop, controller unknown; decision 0043) setting
/// `asked`, and the fields of TwoStageOptions as flags that need it, all in `group`; `path`
/// names the options in messages.
void add_two_stage_flags(CLI::App& app, bool& asked, TwoStageOptions& options,
                         const std::string& flag, const std::string& path, const std::string& group,
                         const std::string& description);

}  // namespace ctid::cli
