// Python bindings of the frequency layer: parametric frequency responses on a grid and the
// nonparametric FRFs (periodic averaging, Welch H1 with coherence) with resonance peaks.
#include "common.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/peaks.h"
#include "ctid/frequency/response.h"
#include "fields.h"

namespace ctid::python {

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
        py::arg("h"), py::arg("hold") = Hold::zero_order_hold,
        "The model's response from u_k to y_k for an input held as `hold` says (the exact "
        "discrete equivalent at e^{j omega h}, delay included): what a nonparametric FRF of "
        "sampled data estimates.");
  m.def("submodel_frequency_responses", &submodel_frequency_responses, py::arg("g"),
        py::arg("omegas"), "Column i: submodel i's response (no delay factor).");

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
  m.def("excited_lines", &excited_lines, py::arg("frf"), py::arg("line_threshold"),
        "The lines of an Frf whose input_level exceeds line_threshold.");

  py::class_<PeriodogramPeak>(m, "PeriodogramPeak", "A periodogram peak above its local floor.")
      .def_readonly("frequency", &PeriodogramPeak::frequency,
                    "rad/s, by parabolic interpolation of log power.")
      .def_readonly("ratio", &PeriodogramPeak::ratio, "Periodogram over its local floor.")
      .def("__repr__", [](const PeriodogramPeak& p) {
        return "PeriodogramPeak(frequency=" + std::to_string(p.frequency) +
               ", ratio=" + std::to_string(p.ratio) + ")";
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
