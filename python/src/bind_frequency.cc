// Python bindings of the frequency layer: parametric frequency responses on a grid and the
// nonparametric FRFs (periodic averaging, Welch H1 with coherence) with resonance peaks.
#include "common.h"
#include "ctid/frequency/frf.h"
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
  m.def("submodel_frequency_responses", &submodel_frequency_responses, py::arg("g"),
        py::arg("omegas"), "Column i: submodel i's response (no delay factor).");

  bind_result<Frf>(m,
                   "A nonparametric FRF on DFT lines: frequencies [rad/s], response, variance "
                   "E|G_hat - G|^2 per line, coherence (Welch only).");
  OptionsClass<PeriodicFrfOptions>(m, "PeriodicFrfOptions", "Options of periodic_frf.")
      .field("period_length", &PeriodicFrfOptions::period_length, "N samples per period.")
      .field("transient_periods", &PeriodicFrfOptions::transient_periods,
             "Periods dropped at the start.")
      .field("lines", &PeriodicFrfOptions::lines, "DFT lines to estimate; empty: excited ones.")
      .field("line_threshold", &PeriodicFrfOptions::line_threshold,
             "Relative input amplitude that counts as excited.")
      .finish();
  OptionsClass<WelchOptions>(m, "WelchOptions", "Options of welch_frf.")
      .field("segment_length", &WelchOptions::segment_length, "L samples per segment.")
      .field("overlap", &WelchOptions::overlap, "Fraction shared by neighbours, [0, 1).")
      .finish();
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
  OptionsClass<PeakOptions>(m, "PeakOptions", "Options of resonance_peaks.")
      .field("min_prominence_db", &PeakOptions::min_prominence_db, "Smallest prominence [dB].")
      .field("max_peaks", &PeakOptions::max_peaks, "Keep the most prominent (0: all).")
      .finish();
  m.def(
      "resonance_peaks",
      [](const Eigen::VectorXd& frequencies, const Eigen::VectorXcd& response,
         const std::optional<PeakOptions>& options, const py::kwargs& kwargs) {
        return resonance_peaks(frequencies, response,
                               options_from<PeakOptions>("resonance_peaks", options, kwargs));
      },
      py::arg("frequencies"), py::arg("response"), py::arg("options") = py::none(),
      "Resonance peaks of |G| in increasing frequency (for orders and initial modes).");
}

}  // namespace ctid::python
