// Python bindings of the simulation layer: exact ZOH/FOH discretisation, ZOH simulation of
// transfer functions and additive models, the sampled-data closed loop, excitation signals
// (white noise, PRBS, multisine) and the continuous loop with delayed feedback.
#include "common.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/delayed_feedback.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "ctid/simulation/stamps.h"
#include "fields.h"

namespace ctid::python {

void bind_simulation(py::module_& m) {
  // Discretisation.
  py::class_<ZohDiscretization>(m, "ZohDiscretization", "x_{k+1} = phi x_k + gamma u_k.")
      .def_readonly("phi", &ZohDiscretization::phi, "e^{A h}.")
      .def_readonly("gamma", &ZohDiscretization::gamma, "int_0^h e^{A s} ds B.");
  py::class_<FohDiscretization>(m, "FohDiscretization",
                                "x_{k+1} = phi x_k + gamma0 u_k + gamma1 u_{k+1}.")
      .def_readonly("phi", &FohDiscretization::phi, "e^{A h}.")
      .def_readonly("gamma0", &FohDiscretization::gamma0, "Weight of u_k.")
      .def_readonly("gamma1", &FohDiscretization::gamma1, "Weight of u_{k+1}.");
  m.def("discretize_zoh",
        py::overload_cast<const Eigen::MatrixXd&, const Eigen::MatrixXd&, double>(&discretize_zoh),
        py::arg("a"), py::arg("b"), py::arg("sample_time"),
        "Exact ZOH discretisation of dx = A x + B u (augmented matrix exponential).");
  m.def("discretize_zoh", py::overload_cast<const StateSpace&, double>(&discretize_zoh),
        py::arg("model"), py::arg("sample_time"),
        "ZOH equivalent (Phi, Gamma, C, D) of a realisation.");
  m.def("discretize_foh", &discretize_foh, py::arg("a"), py::arg("b"), py::arg("sample_time"),
        "Exact FOH (triangle-hold) discretisation.");

  // ZOH simulation.
  m.def("delay_in_samples", &delay_in_samples, py::arg("delay"), py::arg("sample_time"),
        "delay / sample_time as an integer; ValueError unless within 1e-9 of one.");
  m.def("simulate_discrete", &simulate_discrete, py::arg("discrete"), py::arg("u"),
        "Response from rest of a discrete realisation.");
  m.def("zoh_equivalent", py::overload_cast<const TransferFunction&, double>(&zoh_equivalent),
        py::arg("g"), py::arg("sample_time"),
        "Exact discrete model from u_k to y_k (delay as states).");
  m.def("zoh_equivalent", py::overload_cast<const AdditiveModel&, double>(&zoh_equivalent),
        py::arg("g"), py::arg("sample_time"), "Exact discrete model of an additive model.");
  m.def("simulate",
        py::overload_cast<const TransferFunction&, const Eigen::VectorXd&, double>(&simulate),
        py::arg("g"), py::arg("u"), py::arg("sample_time"),
        "Samples y_k of the response of G to the ZOH input u, from rest.");
  m.def("simulate",
        py::overload_cast<const AdditiveModel&, const Eigen::VectorXd&, double>(&simulate),
        py::arg("g"), py::arg("u"), py::arg("sample_time"), "The same for an additive model.");
  m.def("simulate_submodels", &simulate_submodels, py::arg("g"), py::arg("u"),
        py::arg("sample_time"),
        "Column i: response of submodel i (rows sum to simulate(g, u, h)).");

  // At irregular time stamps (decision 0053).
  m.def("simulate_on_stamps",
        py::overload_cast<const TransferFunction&, const Eigen::VectorXd&, const Eigen::VectorXd&,
                          Hold>(&simulate_on_stamps),
        py::arg("g"), py::arg("time"), py::arg("u"), py::arg("hold") = Hold::zero_order_hold,
        "y(t_k) of G driven by u_k at the stamps t_k (non-decreasing, equal stamps allowed), "
        "held as `hold` says, from rest at t_0; nothing resampled.");
  m.def(
      "simulate_on_stamps",
      py::overload_cast<const AdditiveModel&, const Eigen::VectorXd&, const Eigen::VectorXd&, Hold>(
          &simulate_on_stamps),
      py::arg("g"), py::arg("time"), py::arg("u"), py::arg("hold") = Hold::zero_order_hold,
      "The same for an additive model.");

  // Sampled-data closed loop.
  py::class_<ClosedLoopSimulation>(m, "ClosedLoopSimulation",
                                   "Result of simulate_closed_loop: input u, output y "
                                   "(noise included) and the noise-free output.")
      .def_readonly("input", &ClosedLoopSimulation::input, "u_k.")
      .def_readonly("output", &ClosedLoopSimulation::output, "y_k with noise.")
      .def_readonly("noise_free_output", &ClosedLoopSimulation::noise_free_output, "(G u)(t_k).");
  m.def("closed_loop_poles", &closed_loop_poles, py::arg("discrete_plant"), py::arg("controller"),
        "Discrete closed-loop poles (hidden modes included).");
  m.def("simulate_closed_loop",
        py::overload_cast<const TransferFunction&, const DiscreteTransferFunction&,
                          const Eigen::VectorXd&, const Eigen::VectorXd&>(&simulate_closed_loop),
        py::arg("plant"), py::arg("controller"), py::arg("reference"),
        py::arg("noise") = Eigen::VectorXd(),
        "Loop r -> C_d(q) -> ZOH -> G -> y (+ noise); ValueError if unstable.");
  m.def("simulate_closed_loop",
        py::overload_cast<const AdditiveModel&, const DiscreteTransferFunction&,
                          const Eigen::VectorXd&, const Eigen::VectorXd&>(&simulate_closed_loop),
        py::arg("plant"), py::arg("controller"), py::arg("reference"),
        py::arg("noise") = Eigen::VectorXd(), "The same for an additive plant.");
  m.def("simulate_closed_loop",
        py::overload_cast<const StateSpace&, const DiscreteTransferFunction&,
                          const Eigen::VectorXd&, const Eigen::VectorXd&>(&simulate_closed_loop),
        py::arg("discrete_plant"), py::arg("controller"), py::arg("reference"),
        py::arg("noise") = Eigen::VectorXd(), "The same for a discrete ZOH plant.");
  m.def("analog_closed_loop_poles", &analog_closed_loop_poles, py::arg("plant"),
        py::arg("controller"),
        "Poles of the analog loop u = C(p)(r - y): roots of den(G) den(C) + num(G) num(C).");
  m.def("simulate_closed_loop",
        py::overload_cast<const TransferFunction&, const TransferFunction&, const Eigen::VectorXd&,
                          double, const Eigen::VectorXd&, Hold>(&simulate_closed_loop),
        py::arg("plant"), py::arg("controller"), py::arg("reference"), py::arg("sample_time"),
        py::arg("noise") = Eigen::VectorXd(), py::arg("hold") = Hold::zero_order_hold,
        "Analog loop u = C(p)(r - y) around G(p), sampled every sample_time: r held as `hold` "
        "says, the noise held (zoh) as a disturbance the controller sees; exact at the "
        "samples. ValueError if the loop is ill-posed or unstable.");

  // Excitation.
  m.def("white_noise", &white_noise, py::arg("length"), py::arg("standard_deviation"),
        py::arg("seed"), "Seeded zero-mean Gaussian white noise (std::mt19937_64).");
  bind_options<PrbsOptions>(m, "Options of a maximum-length PRBS.");
  m.def(
      "prbs_period",
      [](const std::optional<PrbsOptions>& options, const py::kwargs& kwargs) {
        return prbs_period(options_from<PrbsOptions>("prbs_period", options, kwargs));
      },
      py::arg("options") = py::none(), "Samples per period, (2^n - 1) * samples_per_bit.");
  m.def(
      "prbs",
      [](int length, const std::optional<PrbsOptions>& options, const py::kwargs& kwargs) {
        return prbs(length, options_from<PrbsOptions>("prbs", options, kwargs));
      },
      py::arg("length"), py::arg("options") = py::none(),
      "length samples of a maximum-length PRBS; options as PrbsOptions or keywords.");
  bind_enum<FrequencyGrid>(m, "FrequencyGrid", "Which DFT lines a multisine excites.");
  bind_options<MultisineOptions>(m, "Options of a random-phase multisine.");
  py::class_<Multisine>(m, "Multisine", "A multisine: signal, excited lines, phases.")
      .def_readonly("signal", &Multisine::signal, "periods * period_length samples.")
      .def_readonly("lines", &Multisine::lines, "Excited DFT lines k (k / (N h) Hz).")
      .def_readonly("phases", &Multisine::phases, "Phase of each line [rad].")
      .def_readonly("amplitude", &Multisine::amplitude, "Amplitude of every line.")
      .def_readonly("period_length", &Multisine::period_length, "N.");
  m.def(
      "multisine",
      [](const std::optional<MultisineOptions>& options, const py::kwargs& kwargs) {
        return multisine(options_from<MultisineOptions>("multisine", options, kwargs));
      },
      py::arg("options") = py::none(),
      "Random-phase multisine, flat on a band; options as MultisineOptions or keywords.");
  py::class_<OrthogonalMultisines>(m, "OrthogonalMultisines",
                                   "Hadamard-phased multisines for several inputs.")
      .def_readonly("experiments", &OrthogonalMultisines::experiments,
                    "n_e arrays of (samples, n_u): the inputs of each experiment.")
      .def_readonly("lines", &OrthogonalMultisines::lines, "Excited DFT lines.")
      .def_readonly("hadamard", &OrthogonalMultisines::hadamard, "n_e x n_e signs.");
  m.def(
      "orthogonal_multisines",
      [](int inputs, const std::optional<MultisineOptions>& options, const py::kwargs& kwargs) {
        return orthogonal_multisines(
            options_from<MultisineOptions>("orthogonal_multisines", options, kwargs), inputs);
      },
      py::arg("inputs"), py::arg("options") = py::none(),
      "n_e = next power of two >= inputs experiments; input i is hadamard[e, i] times the "
      "multisine seeded seed + i (for periodic_frf of a MIMO system).");
  m.def("repeat_periodic", &repeat_periodic, py::arg("period"), py::arg("periods"),
        "periods copies of period one after another.");

  // Coloured noise.
  m.def("stationary_run_in", &stationary_run_in, py::arg("filter"), py::arg("tolerance") = 1e-12,
        "Samples discarded so that filtered noise is stationary to the tolerance.");
  m.def("stationary_variance_gain", &stationary_variance_gain, py::arg("filter"),
        "Stationary output variance of the filter for unit-variance white input.");
  m.def("colored_noise", &colored_noise, py::arg("filter"), py::arg("length"), py::arg("variance"),
        py::arg("seed"), py::arg("run_in") = -1,
        "Stationary noise H(q) e with white e of the given variance (seeded).");
  m.def("snr_db", &snr_db, py::arg("signal"), py::arg("noise"),
        "10 log10(var(signal) / var(noise)).");
  m.def("scale_noise_to_snr", &scale_noise_to_snr, py::arg("signal"), py::arg("noise"),
        py::arg("snr"), "The noise scaled so that snr_db(signal, result) == snr.");

  // Continuous loop with delayed feedback.
  py::class_<DelayedFeedbackLoop>(m, "DelayedFeedbackLoop",
                                  "e = u - (H y)(t - delay), y = F e; F, H strictly proper.")
      .def(py::init([](TransferFunction f, TransferFunction h, double delay) {
             DelayedFeedbackLoop loop{std::move(f), std::move(h), delay};
             loop.validate();
             return loop;
           }),
           py::arg("forward"), py::arg("feedback"), py::arg("delay"), "Checked loop.")
      .def_readwrite("forward", &DelayedFeedbackLoop::forward, "F(s).")
      .def_readwrite("feedback", &DelayedFeedbackLoop::feedback, "H(s).")
      .def_readwrite("delay", &DelayedFeedbackLoop::delay, "Delta [s].")
      .def("validate", &DelayedFeedbackLoop::validate, "Raise ValueError on a broken rule.")
      .def("closed_loop_response", &DelayedFeedbackLoop::closed_loop_response, py::arg("s"),
           "W(s) = F / (1 + F H e^{-Delta s}).")
      .def("alpha", &DelayedFeedbackLoop::alpha, "alpha = N_F D_H (monic normalisation).")
      .def("beta", &DelayedFeedbackLoop::beta, "beta = D_F D_H (monic).")
      .def("gamma", &DelayedFeedbackLoop::gamma, "gamma = N_F N_H.");
  py::class_<DelayedStateSpace>(m, "DelayedStateSpace",
                                "dx = A x + B u + E z(t - delay), z = G x, y = C x.")
      .def_readwrite("a", &DelayedStateSpace::a, "A.")
      .def_readwrite("b", &DelayedStateSpace::b, "B.")
      .def_readwrite("e", &DelayedStateSpace::e, "E.")
      .def_readwrite("c", &DelayedStateSpace::c, "C.")
      .def_readwrite("g", &DelayedStateSpace::g, "G.")
      .def_readwrite("delay", &DelayedStateSpace::delay, "Delta [s].")
      .def("validate", &DelayedStateSpace::validate, "Raise ValueError on bad sizes.");
  m.def("to_delayed_state_space",
        py::overload_cast<const DelayedFeedbackLoop&>(&to_delayed_state_space), py::arg("loop"),
        "Delayed realisation of the loop.");
  m.def("to_delayed_state_space",
        py::overload_cast<const Polynomial&, const Polynomial&, const Polynomial&, double>(
            &to_delayed_state_space),
        py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("delay"),
        "Realisation of W = alpha / (beta + gamma e^{-Delta s}).");
  bind_options<DelayedSimulationOptions>(m, "Options of simulate_delayed.");
  m.def(
      "simulate_delayed",
      [](const DelayedStateSpace& model, const std::function<double(double)>& input,
         double sample_time, int samples, const std::optional<DelayedSimulationOptions>& options,
         const py::kwargs& kwargs) {
        return simulate_delayed(
            model, input, sample_time, samples,
            options_from<DelayedSimulationOptions>("simulate_delayed", options, kwargs));
      },
      py::arg("model"), py::arg("input"), py::arg("sample_time"), py::arg("samples"),
      py::arg("options") = py::none(),
      "Output samples y(k h) for an input given as a function of time.");
  m.def(
      "simulate_delayed",
      [](const DelayedStateSpace& model, const Eigen::VectorXd& input, double sample_time,
         Hold hold, const std::optional<DelayedSimulationOptions>& options,
         const py::kwargs& kwargs) {
        return simulate_delayed(
            model, input, sample_time, hold,
            options_from<DelayedSimulationOptions>("simulate_delayed", options, kwargs));
      },
      py::arg("model"), py::arg("input"), py::arg("sample_time"), py::arg("hold"),
      py::arg("options") = py::none(), "Output samples for a sampled input and a hold.");
  py::class_<FourierBasisInput>(m, "FourierBasisInput",
                                "u(t) = 1 + sum_k sqrt2 (sin + cos)(2 pi k t / T).")
      .def(py::init([](int harmonics, double period) {
             return FourierBasisInput{harmonics, period};
           }),
           py::arg("harmonics") = 12, py::arg("period") = 5.0, "K harmonics, period T.")
      .def_readwrite("harmonics", &FourierBasisInput::harmonics, "K.")
      .def_readwrite("period", &FourierBasisInput::period, "T [s].")
      .def("__call__", &FourierBasisInput::operator(), py::arg("t"), "u(t).");
  py::class_<NoisyOutput>(m, "NoisyOutput", "signal + noise, and the noise.")
      .def_readonly("output", &NoisyOutput::output, "signal + noise.")
      .def_readonly("noise", &NoisyOutput::noise, "The noise.");
  m.def("add_noise_at_nsr", &add_noise_at_nsr, py::arg("signal"), py::arg("noise_to_signal"),
        py::arg("seed"), "White noise scaled to mean|noise| / mean|signal| = NSR exactly.");
}

}  // namespace ctid::python
