// Python bindings of the core layer: Polynomial (ascending coefficients), TransferFunction,
// DiscreteTransferFunction, StateSpace, AdditiveModel with its submodels, SampledData and its
// preprocessing.
#include <complex>

#include "common.h"
#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/hold.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/mimo_preprocessing.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/preprocessing.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/state_space.h"
#include "ctid/core/transfer_function.h"
#include "ctid/io/result_json.h"
#include "fields.h"

namespace ctid::python {

void bind_core(py::module_& m) {
  bind_enum<Hold>(m, "Hold", "How a sampled signal continues between samples (core/hold.h).");
  bind_options_json(m);
  using Complex = std::complex<double>;

  py::class_<Polynomial>(m, "Polynomial",
                         "Real polynomial with coefficients in ASCENDING powers: "
                         "Polynomial([c0, c1, c2]) is c0 + c1 x + c2 x^2.")
      .def(py::init<>(), "The zero polynomial (degree -1).")
      .def(py::init<Eigen::VectorXd>(), py::arg("coefficients"),
           "From ascending coefficients; a zero leading coefficient raises ValueError.")
      .def_static("trimmed", &Polynomial::trimmed, py::arg("coefficients"),
                  py::arg("tolerance") = 0.0,
                  "Drop leading coefficients with |c| <= tolerance * max|c|.")
      .def_static("from_roots", &Polynomial::from_roots, py::arg("roots"), py::arg("leading") = 1.0,
                  "leading * prod(x - r_i); complex roots in pairs.")
      .def_property_readonly("coefficients", &Polynomial::coefficients,
                             "Ascending coefficients (empty for the zero polynomial).")
      .def("degree", &Polynomial::degree, "Degree; -1 for the zero polynomial.")
      .def("roots", &Polynomial::roots, "Roots (balanced companion eigenvalues).")
      .def("derivative", &Polynomial::derivative, "The derivative polynomial.")
      .def("monic", &Polynomial::monic, "Divided by its leading coefficient.")
      .def("anti_monic", &Polynomial::anti_monic, "Divided by its constant coefficient.")
      .def(
          "__call__", [](const Polynomial& p, Complex x) { return p(x); }, py::arg("x"),
          "Value at a (complex) point.")
      .def(py::self + py::self)
      .def(py::self - py::self)
      .def(py::self * py::self)
      .def(py::self == py::self)
      .def("to_string", &Polynomial::to_string, py::arg("variable") = "s",
           "Human-readable form, highest power first.")
      .def("__repr__", [](const Polynomial& p) { return "Polynomial(" + p.to_string() + ")"; });
  py::implicitly_convertible<py::list, Polynomial>();
  py::implicitly_convertible<py::array, Polynomial>();

  py::class_<StateSpace>(m, "StateSpace",
                         "SISO state space dx = A x + B u, y = C x + D u (or the discrete "
                         "x_{k+1} = A x_k + B u_k).")
      .def(py::init([](Eigen::MatrixXd a, Eigen::VectorXd b, Eigen::RowVectorXd c, double d) {
             StateSpace s{std::move(a), std::move(b), std::move(c), d};
             s.validate();
             return s;
           }),
           py::arg("a"), py::arg("b"), py::arg("c"), py::arg("d") = 0.0,
           "From the matrices; inconsistent sizes or non-finite entries raise ValueError.")
      .def_readwrite("a", &StateSpace::a, "State matrix A.")
      .def_readwrite("b", &StateSpace::b, "Input vector B.")
      .def_readwrite("c", &StateSpace::c, "Output row C.")
      .def_readwrite("d", &StateSpace::d, "Feedthrough D.")
      .def("order", &StateSpace::order, "Number of states.")
      .def("validate", &StateSpace::validate, "Raise ValueError on inconsistent sizes.");

  py::class_<TransferFunction>(m, "TransferFunction",
                               "Continuous-time G(s) = e^{-s tau} N(s)/D(s), ascending "
                               "coefficients, optional input delay tau in seconds.")
      .def(py::init<Polynomial, Polynomial, double>(), py::arg("numerator"), py::arg("denominator"),
           py::arg("input_delay") = 0.0,
           "From numerator and denominator (Polynomial or ascending coefficient lists).")
      // Coefficient lists that the implicit conversion to Polynomial refused (a NaN, say) reach
      // this overload, whose Polynomial raises ValueError saying why, instead of pybind's
      // TypeError listing signatures (issue 33).
      .def(py::init([](const Eigen::VectorXd& numerator, const Eigen::VectorXd& denominator,
                       double input_delay) {
             return TransferFunction(Polynomial(numerator), Polynomial(denominator), input_delay);
           }),
           py::arg("numerator"), py::arg("denominator"), py::arg("input_delay") = 0.0)
      .def_property_readonly("numerator", &TransferFunction::numerator, "N(s).")
      .def_property_readonly("denominator", &TransferFunction::denominator, "D(s).")
      .def_property_readonly("input_delay", &TransferFunction::input_delay, "tau [s].")
      .def("with_input_delay", &TransferFunction::with_input_delay, py::arg("delay"),
           "Copy with another input delay.")
      .def("poles", &TransferFunction::poles, "Roots of D.")
      .def("zeros", &TransferFunction::zeros, "Roots of N.")
      .def("dc_gain", &TransferFunction::dc_gain, "N(0)/D(0).")
      .def(
          "__call__", [](const TransferFunction& g, Complex s) { return g(s); }, py::arg("s"),
          "G(s) including the delay factor.")
      .def("frequency_response",
           py::overload_cast<double>(&TransferFunction::frequency_response, py::const_),
           py::arg("omega"), "G(j omega), omega in rad/s.")
      .def("relative_degree", &TransferFunction::relative_degree, "deg D - deg N.")
      .def("is_proper", &TransferFunction::is_proper, "deg N <= deg D.")
      .def("is_strictly_proper", &TransferFunction::is_strictly_proper, "deg N < deg D.")
      .def("is_biproper", &TransferFunction::is_biproper, "deg N == deg D.")
      .def("is_stable", &TransferFunction::is_stable, "Every pole in the open left half-plane.")
      .def("normalized", &TransferFunction::normalized, "Same model with a monic denominator.")
      .def("to_state_space", &TransferFunction::to_state_space,
           "Scaled, balanced minimal realisation (delay not included).")
      .def_static("from_state_space", &TransferFunction::from_state_space, py::arg("model"),
                  "Transfer function of a realisation.")
      .def(py::self + py::self)
      .def(py::self * py::self)
      .def("to_string", &TransferFunction::to_string, "Human-readable form.")
      .def("__repr__", &TransferFunction::to_string);

  py::class_<DiscreteTransferFunction>(
      m, "DiscreteTransferFunction",
      "Discrete-time G(q) = N(q)/D(q) in the shift operator q, ascending coefficients, with a "
      "sample time (controllers, noise filters).")
      .def(py::init<Polynomial, Polynomial, double>(), py::arg("numerator"), py::arg("denominator"),
           py::arg("sample_time"), "Proper model, sample time > 0.")
      .def(py::init([](const Eigen::VectorXd& numerator, const Eigen::VectorXd& denominator,
                       double sample_time) {
             return DiscreteTransferFunction(Polynomial(numerator), Polynomial(denominator),
                                             sample_time);
           }),
           py::arg("numerator"), py::arg("denominator"), py::arg("sample_time"))
      .def_property_readonly("numerator", &DiscreteTransferFunction::numerator, "N(q).")
      .def_property_readonly("denominator", &DiscreteTransferFunction::denominator, "D(q).")
      .def_property_readonly("sample_time", &DiscreteTransferFunction::sample_time, "h [s].")
      .def("poles", &DiscreteTransferFunction::poles, "Roots of D.")
      .def("zeros", &DiscreteTransferFunction::zeros, "Roots of N.")
      .def("dc_gain", &DiscreteTransferFunction::dc_gain, "N(1)/D(1).")
      .def(
          "__call__", [](const DiscreteTransferFunction& g, Complex z) { return g(z); },
          py::arg("z"), "G(z).")
      .def("frequency_response",
           py::overload_cast<double>(&DiscreteTransferFunction::frequency_response, py::const_),
           py::arg("omega"), "G(e^{j omega h}), omega in rad/s.")
      .def("is_biproper", &DiscreteTransferFunction::is_biproper, "deg N == deg D.")
      .def("is_stable", &DiscreteTransferFunction::is_stable, "Poles inside the unit circle.")
      .def("to_state_space", &DiscreteTransferFunction::to_state_space,
           "Controllable-form realisation.")
      .def("filter", &DiscreteTransferFunction::filter, py::arg("x"), "y = G(q) x from rest.")
      .def("to_string", &DiscreteTransferFunction::to_string, "Human-readable form.")
      .def("__repr__", &DiscreteTransferFunction::to_string);

  py::class_<Submodel>(m, "Submodel",
                       "One term B(p)/(p^l A(p)) of an additive model; A anti-monic (A(0)=1).")
      .def(py::init([](Polynomial a, Polynomial b, int integrators) {
             return Submodel{std::move(a), std::move(b), integrators};
           }),
           py::arg("a"), py::arg("b"), py::arg("integrators") = 0,
           "From A (ascending, a[0] == 1), B and the number of poles at the origin.")
      .def_readwrite("a", &Submodel::a, "Anti-monic denominator A.")
      .def_readwrite("b", &Submodel::b, "Numerator B.")
      .def_readwrite("integrators", &Submodel::integrators, "Poles at the origin l.")
      .def("n", &Submodel::n, "deg A.")
      .def("m", &Submodel::m, "deg B.")
      .def("parameter_count", &Submodel::parameter_count, "n + m + 1.")
      .def("__repr__", &Submodel::to_string)
      .def("is_biproper", &Submodel::is_biproper, "m == n + l.")
      .def("to_transfer_function", &Submodel::to_transfer_function, "B/(p^l A).");

  py::class_<ModalParameters>(m, "ModalParameters",
                              "Natural frequency [rad/s], damping ratio and modal gain of a "
                              "second-order submodel.")
      .def(py::init([](double w, double zeta, double gain) {
             return ModalParameters{w, zeta, gain};
           }),
           py::arg("natural_frequency") = 0.0, py::arg("damping_ratio") = 0.0,
           py::arg("gain") = 0.0, "From the three values.")
      .def_readwrite("natural_frequency", &ModalParameters::natural_frequency, "w_n [rad/s].")
      .def_readwrite("damping_ratio", &ModalParameters::damping_ratio, "zeta.")
      .def_readwrite("gain", &ModalParameters::gain, "B(0).")
      .def("__repr__", [](const ModalParameters& p) {
        return "ModalParameters(natural_frequency=" + format_brief(p.natural_frequency) +
               ", damping_ratio=" + format_brief(p.damping_ratio) +
               ", gain=" + format_brief(p.gain) + ")";
      });

  py::class_<SubmodelOrder>(m, "SubmodelOrder",
                            "Requested structure of one submodel: n poles (besides the "
                            "origin), m zeros, integrators poles at the origin.")
      .def(py::init([](int n, int m_, int integrators) {
             return SubmodelOrder{n, m_, integrators};
           }),
           py::arg("n") = 2, py::arg("m") = 0, py::arg("integrators") = 0, "From the orders.")
      .def_readwrite("n", &SubmodelOrder::n, "deg A.")
      .def_readwrite("m", &SubmodelOrder::m, "deg B.")
      .def_readwrite("integrators", &SubmodelOrder::integrators, "Poles at the origin.")
      .def("__repr__", [](const SubmodelOrder& o) {
        return "SubmodelOrder(n=" + std::to_string(o.n) + ", m=" + std::to_string(o.m) +
               ", integrators=" + std::to_string(o.integrators) + ")";
      });

  py::class_<AdditiveModel>(m, "AdditiveModel",
                            "G(p) = e^{-p tau} sum_i B_i(p)/(p^l_i A_i(p)), anti-monic A_i; "
                            "parameters theta_i = [a_i1..a_in, b_i0..b_im] stacked.")
      .def(py::init<std::vector<Submodel>, double>(), py::arg("submodels"),
           py::arg("input_delay") = 0.0, "From submodels; every rule is checked.")
      .def(py::init(&io::as_additive_model), py::arg("transfer_function"),
           "One submodel B/(p^l A) holding the transfer function (A anti-monic, its "
           "integrators counted, its delay kept); how a TransferFunction is taken wherever an "
           "AdditiveModel is asked for.")
      .def_static("from_parameters", &AdditiveModel::from_parameters, py::arg("orders"),
                  py::arg("theta"), py::arg("input_delay") = 0.0,
                  "From orders and the stacked parameter vector.")
      .def_static("from_transfer_function", &AdditiveModel::from_transfer_function, py::arg("g"),
                  py::arg("imag_tolerance") = 1e-8,
                  "Partial-fraction split into first/second-order submodels.")
      .def_property_readonly("submodels", &AdditiveModel::submodels, "The submodels.")
      .def_property_readonly("input_delay", &AdditiveModel::input_delay, "tau [s].")
      .def("__len__", &AdditiveModel::size)
      .def("__getitem__", &AdditiveModel::operator[], py::arg("i"))
      .def("size", &AdditiveModel::size, "Number of submodels K.")
      .def("with_input_delay", &AdditiveModel::with_input_delay, py::arg("delay"),
           "Copy with another delay.")
      .def("orders", &AdditiveModel::orders, "SubmodelOrder of each submodel.")
      .def("parameter_count", &AdditiveModel::parameter_count, "Length of theta.")
      .def("parameters", &AdditiveModel::parameters, "Stacked theta.")
      .def("with_parameters", &AdditiveModel::with_parameters, py::arg("theta"),
           "Same structure, new parameters.")
      .def("to_transfer_function", &AdditiveModel::to_transfer_function,
           "The sum as one transfer function.")
      .def("frequency_response",
           py::overload_cast<double>(&AdditiveModel::frequency_response, py::const_),
           py::arg("omega"), "G(j omega), omega in rad/s.")
      .def("modal_parameters", &AdditiveModel::modal_parameters, py::arg("i"),
           "ModalParameters of submodel i if it is an underdamped mode, else None.")
      .def("to_string", &AdditiveModel::to_string, "Human-readable form.")
      .def("__repr__", &AdditiveModel::to_string);
  // A TransferFunction is accepted wherever an AdditiveModel is (overloads that take a
  // TransferFunction itself still come first: pybind11 tries them without conversions).
  py::implicitly_convertible<TransferFunction, AdditiveModel>();

  py::class_<MimoSubmodel>(m, "MimoSubmodel",
                           "One denominator A_i shared by every channel and its numerators "
                           "R_i[j, k] (b[j * inputs + k]).")
      .def(py::init([](Polynomial a, std::vector<Polynomial> b, int integrators) {
             return MimoSubmodel{std::move(a), std::move(b), integrators};
           }),
           py::arg("a"), py::arg("b"), py::arg("integrators") = 0)
      .def_readwrite("a", &MimoSubmodel::a, "Anti-monic denominator A_i.")
      .def_readwrite("b", &MimoSubmodel::b, "Numerators, output by output, input by input.")
      .def_readwrite("integrators", &MimoSubmodel::integrators,
                     "l_i poles at the origin (R_i / (p^l_i A_i); a rigid-body mode: 2).");
  py::class_<MimoAdditiveModel>(m, "MimoAdditiveModel",
                                "G(p) = sum_i R_i(p) / A_i(p) + D: poles shared by every "
                                "input-output pair (MIMO modal model).")
      .def(py::init<int, int, std::vector<MimoSubmodel>, Eigen::MatrixXd, Eigen::VectorXd>(),
           py::arg("inputs"), py::arg("outputs"), py::arg("submodels"),
           py::arg("direct") = Eigen::MatrixXd(), py::arg("input_delays") = Eigen::VectorXd(),
           "From submodels, an optional direct term D (outputs x inputs) and optional "
           "per-input delays [s].")
      .def_property_readonly("inputs", &MimoAdditiveModel::inputs, "n_u.")
      .def_property_readonly("outputs", &MimoAdditiveModel::outputs, "n_y.")
      .def_property_readonly("submodels", &MimoAdditiveModel::submodels, "The submodels.")
      .def_property_readonly("direct", &MimoAdditiveModel::direct, "D (zero if none).")
      .def_property_readonly("has_direct_term", &MimoAdditiveModel::has_direct_term,
                             "Whether D was given.")
      .def_property_readonly("input_delays", &MimoAdditiveModel::input_delays,
                             "tau_k [s] per input (zeros if none).")
      .def("with_input_delays", &MimoAdditiveModel::with_input_delays, py::arg("input_delays"),
           "The same model with these per-input delays [s].")
      .def("__len__", &MimoAdditiveModel::size)
      .def("numerator", &MimoAdditiveModel::numerator, py::arg("i"), py::arg("output"),
           py::arg("input"), "R_i[output, input].")
      .def("channel", &MimoAdditiveModel::channel, py::arg("output"), py::arg("input"),
           "The SISO AdditiveModel of one channel (D folded into the first submodel).");

  py::class_<SampledData>(m, "SampledData",
                          "Uniformly sampled input u, output y and optional reference r at "
                          "t_k = start_time + k h.")
      .def(py::init<double, Eigen::VectorXd, Eigen::VectorXd, std::optional<Eigen::VectorXd>,
                    double>(),
           py::arg("sample_time"), py::arg("input"), py::arg("output"),
           py::arg("reference") = py::none(), py::arg("start_time") = 0.0,
           "Checked: h > 0, equal lengths, >= 2 samples, finite values.")
      .def_static("from_time_stamps", &SampledData::from_time_stamps, py::arg("time"),
                  py::arg("input"), py::arg("output"), py::arg("reference") = py::none(),
                  py::arg("relative_tolerance") = 1e-6, "From uniformly increasing time stamps.")
      .def("__len__", &SampledData::size)
      .def("size", &SampledData::size, "Number of samples N.")
      .def_property_readonly("sample_time", &SampledData::sample_time, "h [s].")
      .def_property_readonly("start_time", &SampledData::start_time, "t_0 [s].")
      .def_property_readonly("time", &SampledData::time, "t_k [s].")
      .def_property_readonly("input", &SampledData::input, "u_k.")
      .def_property_readonly("output", &SampledData::output, "y_k.")
      .def("has_reference", &SampledData::has_reference, "True if r is present.")
      .def_property_readonly(
          "reference",
          [](const SampledData& d) -> std::optional<Eigen::VectorXd> {
            if (!d.has_reference()) return std::nullopt;
            return d.reference();
          },
          "r_k or None.")
      .def_property_readonly("input_hold", &SampledData::input_hold,
                             "How the input is continued between samples (Hold).")
      .def(
          "with_input_hold",
          [](const SampledData& data, Hold hold) { return data.with_input_hold(hold); },
          py::arg("hold"), "The same record with its input continued by `hold`.")
      .def("segment", &SampledData::segment, py::arg("begin"), py::arg("count"),
           "Samples [begin, begin + count) (the input hold is kept).")
      .def(
          "preprocess",
          [](const SampledData& data, const std::optional<PreprocessingOptions>& options,
             const py::kwargs& kwargs) {
            return preprocess(data, options_from<PreprocessingOptions>("SampledData.preprocess",
                                                                       options, kwargs));
          },
          py::arg("options") = py::none(),
          "PreprocessedData: this record after range, detrend, decimation and scaling "
          "(PreprocessingOptions or its fields as keywords).");

  py::class_<MimoData>(m, "MimoData",
                       "Uniformly sampled record with several inputs (N x n_u), outputs (N x "
                       "n_y) and optional references (N x n_u), each channel named.")
      .def(py::init<double, Eigen::MatrixXd, Eigen::MatrixXd, std::optional<Eigen::MatrixXd>,
                    double>(),
           py::arg("sample_time"), py::arg("inputs"), py::arg("outputs"),
           py::arg("references") = py::none(), py::arg("start_time") = 0.0,
           "Checked: h > 0, equal lengths, >= 2 samples, >= 1 input and output, finite values; "
           "channels named u1.., y1.. until with_names.")
      .def(py::init<const SampledData&>(), py::arg("data"), "A SISO record as a 1 x 1 one.")
      .def("__len__", &MimoData::size)
      .def("size", &MimoData::size, "Number of samples N.")
      .def_property_readonly("input_count", &MimoData::input_count, "n_u.")
      .def_property_readonly("output_count", &MimoData::output_count, "n_y.")
      .def_property_readonly("sample_time", &MimoData::sample_time, "h [s].")
      .def_property_readonly("start_time", &MimoData::start_time, "t_0 [s].")
      .def_property_readonly("time", &MimoData::time, "t_k [s].")
      .def_property_readonly("inputs", &MimoData::inputs, "N x n_u inputs.")
      .def_property_readonly("outputs", &MimoData::outputs, "N x n_y outputs.")
      .def("has_references", &MimoData::has_references, "True if references are present.")
      .def_property_readonly(
          "references",
          [](const MimoData& d) -> std::optional<Eigen::MatrixXd> {
            if (!d.has_references()) return std::nullopt;
            return d.references();
          },
          "N x n_u references or None.")
      .def_property_readonly("input_names", &MimoData::input_names, "Names of the inputs.")
      .def_property_readonly("output_names", &MimoData::output_names, "Names of the outputs.")
      .def("with_names", &MimoData::with_names, py::arg("input_names"), py::arg("output_names"),
           "The same record with its channels named (distinct, non-empty names).")
      .def_property_readonly("input_hold", &MimoData::input_hold,
                             "How every input is continued between samples (Hold).")
      .def("with_input_hold", &MimoData::with_input_hold, py::arg("hold"),
           "The same record with its inputs continued by `hold`.")
      .def("segment", &MimoData::segment, py::arg("begin"), py::arg("count"),
           "Samples [begin, begin + count), names and hold kept.")
      .def("channel", &MimoData::channel, py::arg("input"), py::arg("output"),
           "Input `input`, output `output` (0-based) as a SISO SampledData.")
      .def("__repr__", [](const MimoData& d) {
        return ::ctid::internal::concat(
            "MimoData(", d.size(), " samples, h=", format_number(d.sample_time()), ", inputs=[",
            join(d.input_names()), "], outputs=[", join(d.output_names()), "])");
      });

  bind_enum<Detrend>(m, "Detrend", "What preprocess removes from each signal.");
  bind_options<PreprocessingOptions>(m, "Options of preprocess (core/preprocessing.h).");
  bind_result<PreprocessingRecord>(m, "What preprocess did, in the original units.")
      .def("summary", &PreprocessingRecord::summary, "One line, as ctid fit prints it.");
  py::class_<PreprocessedData>(m, "PreprocessedData",
                               "The preprocessed record and the record of what was done.")
      .def_readonly("data", &PreprocessedData::data, "The preprocessed SampledData.")
      .def_readonly("record", &PreprocessedData::record, "The PreprocessingRecord.")
      .def("__repr__", [](const PreprocessedData& p) {
        return "PreprocessedData(" + p.record.summary() + ")";
      });
  m.def(
      "preprocess",
      [](const SampledData& data, const std::optional<PreprocessingOptions>& options,
         const py::kwargs& kwargs) {
        return preprocess(data, options_from<PreprocessingOptions>("preprocess", options, kwargs));
      },
      py::arg("data"), py::arg("options") = py::none(),
      "PreprocessedData: the record after range, detrend, decimation and scaling.");
  m.def("remove_trend", &remove_trend, py::arg("data"), py::arg("trend"),
        "Another record minus the trend an earlier preprocess removed (trend: its "
        "PreprocessingRecord; offset + slope (t - t_0) per signal, t_0 the record's first "
        "sample), as `ctid validate --detrend fit` does. Example: "
        "ctid.remove_trend(validation, fitted_record) before ctid.validate_model.");
  m.def("add_output_trend", &add_output_trend, py::arg("output"), py::arg("sample_time"),
        py::arg("trend"),
        "The output trend of `trend` added back to an output sampled every sample_time from "
        "its first sample: a simulated output at the record's own level.");
  py::class_<PreprocessedMimoData>(
      m, "PreprocessedMimoData",
      "A preprocessed MimoData, the record of what was done and each channel's removed line.")
      .def_readonly("data", &PreprocessedMimoData::data, "The preprocessed MimoData.")
      .def_readonly("record", &PreprocessedMimoData::record,
                    "The PreprocessingRecord (offsets of the first channels, warnings of all).")
      .def_readonly("input_offsets", &PreprocessedMimoData::input_offsets,
                    "Removed offset of each input.")
      .def_readonly("input_slopes", &PreprocessedMimoData::input_slopes,
                    "Removed slope of each input [1/s].")
      .def_readonly("output_offsets", &PreprocessedMimoData::output_offsets,
                    "Removed offset of each output.")
      .def_readonly("output_slopes", &PreprocessedMimoData::output_slopes,
                    "Removed slope of each output [1/s].");
  m.def(
      "preprocess",
      [](const MimoData& data, const std::optional<PreprocessingOptions>& options,
         const py::kwargs& kwargs) {
        return preprocess(data, options_from<PreprocessingOptions>("preprocess", options, kwargs));
      },
      py::arg("data"), py::arg("options") = py::none(),
      "PreprocessedMimoData: every channel of a MimoData preprocessed alike.");
  m.def(
      "resample",
      [](const Eigen::VectorXd& time, const Eigen::VectorXd& input, const Eigen::VectorXd& output,
         double h, const std::optional<Eigen::VectorXd>& reference,
         Hold input_hold) { return resample(time, input, output, reference, h, input_hold); },
      py::arg("time"), py::arg("input"), py::arg("output"), py::arg("sample_time"),
      py::arg("reference") = py::none(), py::arg("input_hold") = Hold::zero_order_hold,
      "A record with irregular time stamps on the uniform grid t_0 + k h: the input as "
      "input_hold says it is held, the output and reference linearly (ctid fit --resample).");
  m.def("check_time_stamps", &check_time_stamps, py::arg("time"),
        py::arg("relative_tolerance") = 1e-6,
        "The uniformity check of time stamps (docs/decisions/0008): step, digits, tolerance "
        "and the stamp farthest off the grid, if beyond tolerance.");
  py::class_<TimeStampCheck>(m, "TimeStampCheck", "Result of check_time_stamps.")
      .def_readonly("step", &TimeStampCheck::step, "h from the first and last stamps [s].")
      .def_readonly("digits", &TimeStampCheck::digits, "Significant digits of the stamps.")
      .def_readonly("tolerance", &TimeStampCheck::tolerance, "Allowed distance from the grid.")
      .def_readonly("worst_sample", &TimeStampCheck::worst_sample,
                    "Stamp farthest off the grid beyond tolerance, or None.")
      .def_readonly("deviation", &TimeStampCheck::deviation, "Its distance from the grid [s].")
      .def("__repr__", [](const TimeStampCheck& c) {
        return ::ctid::internal::concat(
            "TimeStampCheck(step=", c.step, ", digits=", c.digits, ", tolerance=", c.tolerance,
            ", worst_sample=", c.worst_sample ? std::to_string(*c.worst_sample) : "None", ")");
      });
}

}  // namespace ctid::python
