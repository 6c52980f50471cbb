// Outputs that would destroy something: one check every ctid command goes through before it
// runs (main.cc). An output file (--output, --model-output) may not be an input file of the
// same run (the same file by inode, or by path through symbolic links), and two outputs may
// not be one file; --force does not lift this. Without --force an output file that exists
// is refused. Streams (/dev/null, /dev/stdout onto a terminal or pipe) and folders (--plot,
// the study's --output) are not checked here.
#pragma once

#include <CLI/CLI.hpp>

namespace ctid::cli {

/// The long names of the options that name an output file, without dashes.
inline constexpr const char* kOutputFileOptions[] = {"output", "model-output"};

/// Throws ctid::InvalidArgument naming both options and the file when an output of the
/// parsed `command` is one of its inputs or another of its outputs, or, when the command has
/// a --force flag that was not given, naming the output file that exists. Inputs are the
/// values of every other option and positional argument that name an existing regular file.
void check_output_paths(const CLI::App& command);

}  // namespace ctid::cli
