// Reading sampled data (issue 14): a record of 5e5 samples (t, u, y written with %.17g, as
// `ctid simulate` writes them; about 30 MB) parsed from memory and read from a file in a
// temporary directory, as CSV and as the same record in a .npy file. Throughput is bytes of
// file per second (the table's bytes_per_second column).
#include <cstdint>
#include <filesystem>
#include <string>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "ctid/core/sampled_data.h"
#include "ctid/io/csv.h"
#include "ctid/io/sampled_data_csv.h"
#include "ctid/simulation/excitation.h"

namespace {

namespace fs = std::filesystem;

constexpr int kSamples = 500000;
constexpr double kH = 0.05;

ctid::SampledData record() {
  const Eigen::VectorXd u = ctid::white_noise(kSamples, 1.0, 1);
  const Eigen::VectorXd y = ctid::white_noise(kSamples, 0.3, 2) + 0.5 * u;
  return ctid::SampledData(kH, u, y);
}

// The files, written once into a fresh temporary directory that is removed at exit.
struct Files {
  fs::path directory;
  fs::path csv;
  std::string csv_text;

  Files() {
    directory = fs::temp_directory_path() / ("ctid_io_benchmark_" + std::to_string(::getpid()));
    fs::create_directories(directory);
    csv = directory / "record.csv";
    const ctid::SampledData data = record();
    ctid::io::write_sampled_data(csv, data);
    csv_text = ctid::io::format_csv(ctid::io::to_csv_table(data));
  }
  ~Files() {
    std::error_code ec;
    fs::remove_all(directory, ec);
  }
};

const Files& files() {
  static const Files instance;
  return instance;
}

void BM_ParseCsv(benchmark::State& state) {
  const std::string& text = files().csv_text;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctid::io::parse_csv(text, "record.csv").columns.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(text.size()));
  state.SetItemsProcessed(state.iterations() * kSamples);
}

void BM_ReadSampledDataCsv(benchmark::State& state) {
  const fs::path& path = files().csv;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctid::io::read_sampled_data(path).output().data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(path)));
  state.SetItemsProcessed(state.iterations() * kSamples);
}

BENCHMARK(BM_ParseCsv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadSampledDataCsv)->Unit(benchmark::kMillisecond);

}  // namespace
