// Reading sampled data (issue 14): a record of 5e5 samples (t, u, y written with %.17g, as
// `ctid simulate` writes them; about 27 MB) parsed from memory and read from a file in a
// temporary directory, as CSV and as the same record in a .npy file (12 MB); and the CSV
// with stamps printed to 8 digits (the time-stamp check then works per stamp). Throughput
// is bytes of file per second (the table's bytes_per_second column).
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "ctid/core/sampled_data.h"
#include "ctid/io/csv.h"
#include "ctid/io/npy.h"
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

// The bytes np.save writes for the C-order float64 array [t u y].
std::string npy_bytes(const ctid::SampledData& data) {
  const Eigen::VectorXd t = data.time();
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" +
                       std::to_string(data.size()) + ", 3), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string bytes = "\x93NUMPY\x01";
  bytes += '\0';
  bytes += static_cast<char>(header.size() & 0xff);
  bytes += static_cast<char>(header.size() >> 8);
  bytes += header;
  for (Eigen::Index k = 0; k < data.size(); ++k) {
    for (const double value : {t(k), data.input()(k), data.output()(k)}) {
      char raw[sizeof value];
      std::memcpy(raw, &value, sizeof value);  // little-endian host
      bytes.append(raw, sizeof raw);
    }
  }
  return bytes;
}

// The CSV with stamps printed to 8 significant digits.
std::string short_stamp_csv(const ctid::SampledData& data) {
  std::string text = "t,u,y\n";
  char line[96];
  for (Eigen::Index k = 0; k < data.size(); ++k) {
    const int n = std::snprintf(line, sizeof line, "%.8g,%.17g,%.17g\n",
                                static_cast<double>(k) * kH, data.input()(k), data.output()(k));
    text.append(line, static_cast<size_t>(n));
  }
  return text;
}

// The files, written once into a fresh temporary directory that is removed at exit.
struct Files {
  fs::path directory;
  fs::path csv;
  fs::path npy;
  fs::path short_csv;
  std::string csv_text;

  Files() {
    directory = fs::temp_directory_path() / ("ctid_io_benchmark_" + std::to_string(::getpid()));
    fs::create_directories(directory);
    csv = directory / "record.csv";
    const ctid::SampledData data = record();
    ctid::io::write_sampled_data(csv, data);
    csv_text = ctid::io::format_csv(ctid::io::to_csv_table(data));
    npy = directory / "record.npy";
    std::ofstream(npy, std::ios::binary) << npy_bytes(data);
    short_csv = directory / "short_stamps.csv";
    std::ofstream(short_csv, std::ios::binary) << short_stamp_csv(data);
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

void BM_ReadSampledDataShortStampsCsv(benchmark::State& state) {
  const fs::path& path = files().short_csv;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctid::io::read_sampled_data(path).output().data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(path)));
  state.SetItemsProcessed(state.iterations() * kSamples);
}

void BM_ReadSampledDataNpy(benchmark::State& state) {
  const fs::path& path = files().npy;
  ctid::io::CsvColumns columns;
  columns.time = "0";
  columns.input = "1";
  columns.output = "2";
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctid::io::read_sampled_data(path, columns).output().data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(path)));
  state.SetItemsProcessed(state.iterations() * kSamples);
}

BENCHMARK(BM_ParseCsv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadSampledDataCsv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadSampledDataShortStampsCsv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadSampledDataNpy)->Unit(benchmark::kMillisecond);

}  // namespace
