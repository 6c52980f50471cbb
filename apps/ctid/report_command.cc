// `ctid report`: one self-contained HTML page from result documents (ctid fit, validate, oma
// -o). A thin launcher: the page is written by the Python package (python3 -m ctid.report,
// python/ctid/report.py), found as --plot finds it (plot_support.h), with stdout and stderr
// passed through and its exit status returned. docs/report.md.

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "plot_support.h"

namespace ctid::cli {
namespace {

struct ReportFlags {
  std::vector<std::string> documents;
  std::string output;
  std::string title;
  bool force = false;
};

ExitStatus run_report(const ReportFlags& f) {
  const std::filesystem::path package = require_python_package("ctid report");
  std::vector<std::string> words{python_executable(), "-m", "ctid.report"};
  words.insert(words.end(), f.documents.begin(), f.documents.end());
  words.insert(words.end(), {"--output", f.output});
  if (!f.title.empty()) words.insert(words.end(), {"--title", f.title});
  if (f.force) words.push_back("--force");
  ::setenv("PYTHONPATH", package.string().c_str(), 1);
  ::setenv("MPLBACKEND", "Agg", 1);
  ::setenv("CTID_REPORT_PROG", "ctid report", 1);  // the name its messages and page give
  return static_cast<ExitStatus>(run_python(std::move(words), "python3 -m ctid.report"));
}

Command add_report_command(CLI::App& parent) {
  auto flags = std::make_shared<ReportFlags>();
  ReportFlags& f = *flags;
  CLI::App* app = parent.add_subcommand(
      "report",
      "Write one self-contained HTML page from the documents of fit, validate or oma: the "
      "verdict in words, parameters and modes ± standard errors, the figures, and how they "
      "were made.");
  app->footer(
      "RESULT is what 'ctid fit -o' (one input and output), 'ctid validate -o' or 'ctid oma -o' "
      "wrote; VALIDATION, a second 'ctid validate -o' document, adds the model's check on other "
      "data to a fit. The page embeds its figures and needs no other file. Runs "
      "/usr/bin/python3 -m ctid.report (the Python package, with matplotlib). Exit status: 0 "
      "written, 2 bad usage or input, 1 other error. docs/report.md.");
  app->add_option("documents", f.documents, "RESULT.json [VALIDATION.json]")
      ->required()
      ->expected(1, 2);
  app->add_option("--output,-o", f.output, "The HTML page to write")->required();
  app->add_option("--title", f.title, "The page's title (default: ctid report: RESULT)");
  app->add_flag("--force", f.force, "Replace an existing output");
  Command command;
  command.app = app;
  command.run = [flags] { return run_report(*flags); };
  return command;
}

}  // namespace

CTID_REGISTER_COMMAND(70, add_report_command);

}  // namespace ctid::cli
