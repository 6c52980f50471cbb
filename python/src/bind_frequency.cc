// Python bindings of the frequency layer: parametric frequency responses on a grid and the
// nonparametric FRFs (periodic averaging, Welch H1 with coherence) with resonance peaks.
#include "common.h"
#include "ctid/core/format.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/frequency/peaks.h"
#include "ctid/frequency/response.h"
#include "ctid/frequency/response_band.h"
#include "fields.h"

namespace ctid::python {
namespace {

// Per-line n_y x n_u matrices as one NumPy array of shape (lines, n_y, n_u).
template <class Matrix>
py::array_t<typename Matrix::Scalar> stacked(const std::vector<Matrix>& per_line, int rows,
                                             int cols) {
  py::array_t<typename Matrix::Scalar> out({static_cast<py::ssize_t>(per_line.size()),
                                            static_cast<py::ssize_t>(rows),
                                            static_cast<py::ssize_t>(cols)});
  auto view = out.template mutable_unchecked<3>();
  for (std::size_t l = 0; l < per_line.size(); ++l) {
    for (int j = 0; j < rows; ++j) {
      for (int i = 0; i < cols; ++i) view(static_cast<py::ssize_t>(l), j, i) = per_line[l](j, i);
    }
  }
  return out;
}

void bind_mimo_frf(py::module_& m) {
  py::class_<MimoFrf>(m, "MimoFrf",
                      "An FRF matrix on DFT lines: response[l, j, i] from input i to output j, "
                      "its variance, the multiple coherence of each output, input levels and "
                      "the inputs' condition per line.")
      .def_readonly("lines", &MimoFrf::lines, "DFT line k of each frequency.")
      .def_readonly("frequencies", &MimoFrf::frequencies, "2 pi k / (L h) [rad/s].")
      .def_property_readonly(
          "response",
          [](const MimoFrf& f) { return stacked(f.response, f.output_count(), f.input_count()); },
          "Complex array (lines, n_y, n_u): H[l, j, i] from input i to output j.")
      .def_property_readonly(
          "variance",
          [](const MimoFrf& f) { return stacked(f.variance, f.output_count(), f.input_count()); },
          "Array (lines, n_y, n_u): E|H_hat - H|^2 of each entry.")
      .def_readonly("coherence", &MimoFrf::coherence,
                    "(lines, n_y): multiple coherence of each output with all inputs.")
      .def_readonly("output_power", &MimoFrf::output_power, "(lines, n_y): S_yjyj.")
      .def_readonly("input_level", &MimoFrf::input_level,
                    "(lines, n_u): each input's amplitude over its largest line's.")
      .def_readonly("input_condition", &MimoFrf::input_condition,
                    "Condition of the normalised input spectral matrix per line (1: "
                    "uncorrelated inputs).")
      .def_readonly("averages", &MimoFrf::averages, "Segments (Welch) or periods averaged.")
      .def_readonly("block_length", &MimoFrf::block_length, "L: samples per segment/period.")
      .def_readonly("input_names", &MimoFrf::input_names, "Names of the inputs.")
      .def_readonly("output_names", &MimoFrf::output_names, "Names of the outputs.")
      .def("inputs_correlated", &MimoFrf::inputs_correlated, py::arg("index"),
           py::arg("max_condition") = kCorrelatedInputCondition,
           "Whether input_condition at position `index` exceeds max_condition.")
      .def("channel", &MimoFrf::channel, py::arg("input"), py::arg("output"),
           "The SISO Frf of one entry (its output's multiple coherence, its input's level).")
      .def("__repr__", [](const MimoFrf& f) {
        return ::ctid::internal::concat("MimoFrf(", f.lines.size(), " lines, ", f.output_count(),
                                        " x ", f.input_count(), ", averages=", f.averages, ")");
      });
  m.def(
      "welch_frf",
      [](const MimoData& data, const std::optional<WelchOptions>& options,
         const py::kwargs& kwargs) {
        return welch_frf(data, options_from<WelchOptions>("welch_frf", options, kwargs));
      },
      py::arg("data"), py::arg("options") = py::none(),
      "MimoData: the H1 FRF matrix S_yu S_uu^-1 with multiple coherence and variance.");
  m.def(
      "periodic_frf",
      [](const std::vector<MimoData>& experiments, const std::optional<PeriodicFrfOptions>& options,
         const py::kwargs& kwargs) {
        return periodic_frf(experiments,
                            options_from<PeriodicFrfOptions>("periodic_frf", options, kwargs));
      },
      py::arg("experiments"), py::arg("options") = py::none(),
      "A list of n_e >= n_u periodic MimoData experiments (e.g. Hadamard multisines): the FRF "
      "matrix Y U^-1 averaged over periods, with its variance.");
  m.def(
      "periodic_frf",
      [](const MimoData& record, int experiments, const std::optional<PeriodicFrfOptions>& options,
         const py::kwargs& kwargs) {
        return periodic_frf(
            record, options_from<PeriodicFrfOptions>("periodic_frf", options, kwargs), experiments);
      },
      py::arg("record"), py::arg("experiments"), py::arg("options") = py::none(),
      "One MimoData holding `experiments` periodic experiments of equal length one after "
      "another.");
  m.def("excited_lines", py::overload_cast<const MimoFrf&, double>(&excited_lines), py::arg("frf"),
        py::arg("line_threshold"),
        "The lines of a MimoFrf where every input's level exceeds line_threshold.");
  m.def("summed_power_frf", &summed_power_frf, py::arg("frf"),
        "One Frf for all channels: sqrt(sum |H_ji|^2), the power-weighted multiple coherence, "
        "the smallest input level (for resonance_peaks over all channels).");
}

}  // namespace

void bind_frequency(py::module_& m) {
  m.def("log_frequency_grid", &log_frequency_grid, py::arg("omega_min"), py::arg("omega_max"),
        py::arg("count"), "count log-spaced frequencies [rad/s], both ends included.");
  m.def("frequency_response",
        py::overload_cast<const TransferFunction&, const Eigen::VectorXd&>(&frequency_response),
        py::arg("g"), py::arg("omegas"), "G(j omega) on a grid [rad/s] (delay included).");
  m.def("frequency_response",
        py::overload_cast<const DiscreteTransferFunction&, const Eigen::VectorXd&>(
            &frequency_response),
        py::arg("g"), py::arg("omegas"), "G(e^{j omega h}) on a grid [rad/s].");
  m.def("frequency_response",
        py::overload_cast<const AdditiveModel&, const Eigen::VectorXd&>(&frequency_response),
        py::arg("g"), py::arg("omegas"), "e^{-j omega tau} sum_i G_i(j omega) on a grid.");
  m.def("sampled_frequency_response", &sampled_frequency_response, py::arg("g"), py::arg("omegas"),
        py::arg("sample_time"), py::arg("hold") = Hold::zero_order_hold,
        "The model's response from u_k to y_k for an input held as `hold` says (the exact "
        "discrete equivalent at e^{j omega h}, delay included): what a nonparametric FRF of "
        "sampled data estimates.");
  m.def("submodel_frequency_responses", &submodel_frequency_responses, py::arg("g"),
        py::arg("omegas"), "Column i: submodel i's response (no delay factor).");
  m.def(
      "frequency_response_band",
      [](const AdditiveModel& model, const Eigen::VectorXd& omegas,
         const Eigen::MatrixXd& covariance) {
        FrequencyResponseBand band = frequency_response_band(model, omegas, covariance);
        return py::make_tuple(band.response, band.magnitude_sigma, band.phase_sigma);
      },
      py::arg("model"), py::arg("omegas"), py::arg("covariance"),
      "(G(j omega), sigma of |G|, sigma of arg G [rad]) on a grid: the first-order band of the "
      "covariance of model.parameters() (frequency/response_band.h).");

  bind_result<Frf>(m,
                   "A nonparametric FRF on DFT lines: frequencies [rad/s], response, variance "
                   "E|G_hat - G|^2 per line, squared coherence and relative input level.");
  bind_options<PeriodicFrfOptions>(m, "Options of periodic_frf.");
  bind_options<WelchOptions>(m, "Options of welch_frf.");
  m.def(
      "periodic_frf",
      [](const SampledData& data, const std::optional<PeriodicFrfOptions>& options,
         const py::kwargs& kwargs) {
        return periodic_frf(data,
                            options_from<PeriodicFrfOptions>("periodic_frf", options, kwargs));
      },
      py::arg("data"), py::arg("options") = py::none(),
      "FRF from a periodic experiment, averaged over periods, with its variance per line.");
  m.def(
      "welch_frf",
      [](const SampledData& data, const std::optional<WelchOptions>& options,
         const py::kwargs& kwargs) {
        return welch_frf(data, options_from<WelchOptions>("welch_frf", options, kwargs));
      },
      py::arg("data"), py::arg("options") = py::none(),
      "H1 FRF with Hann-windowed Welch averaging, and the coherence.");
  bind_mimo_frf(m);

  bind_result<ResonancePeak>(m, "A resonance peak of |G|.");
  bind_options<PeakOptions>(m, "Options of resonance_peaks.");
  m.def(
      "resonance_peaks",
      [](const Eigen::VectorXd& frequencies, const Eigen::VectorXcd& response,
         const std::optional<PeakOptions>& options, const py::kwargs& kwargs) {
        return resonance_peaks(frequencies, response,
                               options_from<PeakOptions>("resonance_peaks", options, kwargs));
      },
      py::arg("frequencies"), py::arg("response"), py::arg("options") = py::none(),
      "Resonance peaks of |G| in increasing frequency (for orders and initial modes).");
  m.def(
      "resonance_peaks",
      [](const Frf& frf, const std::optional<PeakOptions>& options, const py::kwargs& kwargs) {
        return resonance_peaks(frf, options_from<PeakOptions>("resonance_peaks", options, kwargs));
      },
      py::arg("frf"), py::arg("options") = py::none(),
      "Resonance peaks of a measured Frf on its excited lines, with their coherence.");
  m.def("excited_lines", py::overload_cast<const Frf&, double>(&excited_lines), py::arg("frf"),
        py::arg("line_threshold"), "The lines of an Frf whose input_level exceeds line_threshold.");

  py::class_<PeriodogramPeak>(m, "PeriodogramPeak", "A periodogram peak above its local floor.")
      .def_readonly("frequency", &PeriodogramPeak::frequency,
                    "rad/s, by parabolic interpolation of log power.")
      .def_readonly("ratio", &PeriodogramPeak::ratio, "Periodogram over its local floor.")
      .def("__repr__", [](const PeriodogramPeak& p) {
        return "PeriodogramPeak(frequency=" + format_brief(p.frequency) +
               ", ratio=" + format_brief(p.ratio) + ")";
      });
  bind_options<PeriodogramPeakOptions>(m, "Options of periodogram_peaks.");
  m.def(
      "periodogram_peaks",
      [](const Eigen::VectorXd& x, double sample_time,
         const std::optional<PeriodogramPeakOptions>& options, const py::kwargs& kwargs) {
        return periodogram_peaks(
            x, sample_time,
            options_from<PeriodogramPeakOptions>("periodogram_peaks", options, kwargs));
      },
      py::arg("x"), py::arg("sample_time"), py::arg("options") = py::none(),
      "Peaks of the zero-padded periodogram of x above its running-median floor, highest "
      "ratio first (as mode relocation finds them in a residual).");
}

}  // namespace ctid::python
