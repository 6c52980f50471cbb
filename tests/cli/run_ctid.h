// Runs the built ctid binary in a shell and captures its exit status, stdout and stderr,
// in a fresh per-test working directory (so relative output paths land there).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Core>

namespace ctid::cli::testing {

struct RunResult {
  int status = -1;
  std::string out;
  std::string err;
};

inline std::string quote(const std::string& word) {
  std::string quoted = "'";
  for (char c : word) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  return quoted + "'";
}

/// "t,u,y" and one row per sample t = k h, every number to 17 significant digits (it reads
/// back bit for bit).
inline std::string tuy_csv(double h, const Eigen::VectorXd& u, const Eigen::VectorXd& y) {
  std::string text = "t,u,y\n";
  char line[120];
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", h * static_cast<double>(k), u(k), y(k));
    text += line;
  }
  return text;
}

inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("ctid_cli_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

  /// Runs `ctid args...` inside the test directory.
  RunResult ctid(const std::vector<std::string>& args) const {
    std::string command = "cd " + quote(dir_.string()) + " && " + quote(CTID_CLI_PATH);
    for (const auto& a : args) command += " " + quote(a);
    command +=
        " > " + quote((dir_ / ".stdout").string()) + " 2> " + quote((dir_ / ".stderr").string());
    const int raw = std::system(command.c_str());
    RunResult r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = slurp(dir_ / ".stdout");
    r.err = slurp(dir_ / ".stderr");
    return r;
  }

  /// Writes a file in the test directory and returns its path.
  std::string write(const std::string& name, const std::string& content) const {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return (dir_ / name).string();
  }

  std::filesystem::path path(const std::string& name) const { return dir_ / name; }

  /// An example model shipped in examples/models/.
  static std::string example(const std::string& name) {
    return std::string(CTID_SOURCE_DIR) + "/examples/models/" + name;
  }

 private:
  std::filesystem::path dir_;
};

/// Number of lines in `text` (a final line without newline counts).
inline int line_count(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n' ? 1 : 0;
  return lines + (!text.empty() && text.back() != '\n' ? 1 : 0);
}

/// Bad input: exit status 2 and one line on stderr, "ctid <command>: error: ..." holding
/// `fragment`.
inline void expect_bad_input(const RunResult& r, const std::string& command,
                             const std::string& fragment) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, ::testing::StartsWith("ctid " + command + ": error: "));
  EXPECT_THAT(r.err, ::testing::HasSubstr(fragment));
}

/// A CliTest whose folder holds d.csv: the Section 6.1 open-loop system (four modes) under
/// four periods of the 0.01-3 Hz multisine of examples/models, noise-free, h = 0.05 s.
class Section61Test : public CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    const auto r =
        ctid({"simulate", "-m", example("gonzalez_6_1_open_loop.json"), "--excitation-spec",
              example("multisine_0.01_3hz.json"), "-o", "d.csv", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }
};

/// The folder of the built ctid Python package, found as plot_support.cc finds it
/// ($CTID_PYTHONPATH, else <build>/python next to the binary); empty when there is none, so
/// --plot tests can skip on builds without Python.
inline std::string python_package() {
  if (const char* env = std::getenv("CTID_PYTHONPATH"); env != nullptr && *env != '\0') {
    return env;
  }
  const std::filesystem::path dir =
      std::filesystem::path(CTID_CLI_PATH).parent_path() / ".." / ".." / "python";
  return std::filesystem::exists(dir / "ctid" / "plot.py") ? dir.string() : "";
}

/// Expects `file` to be a PNG image of at least 300 x 200 pixels (signature, IHDR size).
inline void expect_png(const std::filesystem::path& file) {
  const std::string bytes = slurp(file);
  ASSERT_GT(bytes.size(), 5000u) << file;
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << file;
  auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
    return v;
  };
  EXPECT_EQ(bytes.substr(12, 4), "IHDR") << file;
  EXPECT_GE(be32(16), 300u) << file;
  EXPECT_GE(be32(20), 200u) << file;
}

}  // namespace ctid::cli::testing
