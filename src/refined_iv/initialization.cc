// LSSVF and FRF-peak starts refined by SRIVC (by CLSRIVC in closed loop, after making them
// starts the controller stabilises), and grouping of poles into a requested additive structure.
#include "ctid/refined_iv/initialization.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "core/internal/finite_transfer_function.h"
#include "core/internal/polynomial_if_finite.h"
#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/frf.h"
#include "ctid/refined_iv/srivc.h"
#include "estimation/internal/scaled_least_squares.h"
#include "refined_iv/internal/refined_iv_engine.h"

namespace ctid {

SubmodelOrder unfactored_order(const std::vector<SubmodelOrder>& orders) {
  require(!orders.empty(), "unfactored_order: the structure has no submodels");
  SubmodelOrder total{0, 0, 0};
  for (const SubmodelOrder& o : orders) {
    total.n += o.n;
    total.integrators += o.integrators;
  }
  for (const SubmodelOrder& o : orders) {
    total.m = std::max(total.m, o.m + (total.n - o.n) + (total.integrators - o.integrators));
  }
  return total;
}

namespace {

// LSSVF's parameters [a_1 .. a_n, b_0 .. b_m] at one bandwidth; none when the state-variable
// filter's coefficients or its realisation are not finite (a bandwidth far below 1).
std::optional<Eigen::VectorXd> lssvf_parameters(const SampledData& data, const SubmodelOrder& order,
                                                double bandwidth, int input_delay) {
  require(order.n >= 0 && order.m >= 0 && order.integrators >= 0 &&
              order.n + order.integrators >= 1 && order.m <= order.n + order.integrators,
          "lssvf: impossible orders n = ", order.n, ", m = ", order.m,
          ", integrators = ", order.integrators);
  require(std::isfinite(bandwidth) && bandwidth > 0.0, "lssvf: bandwidth is ", bandwidth,
          "; it must be positive");
  const int d = order.n + order.integrators;
  if (!std::isfinite(1.0 / bandwidth)) return std::nullopt;
  const Polynomial one_pole{1.0, 1.0 / bandwidth};
  std::optional<Polynomial> f = Polynomial{1.0};
  for (int k = 0; k < d && f; ++k) f = internal::product_if_finite(*f, one_pole);
  if (!f) return std::nullopt;
  const double h = data.sample_time();
  const std::optional<FilterRealization> bank = finite_derivative_filters(*f);
  if (!bank) return std::nullopt;
  const Eigen::MatrixXd fy = SampledFilter(*bank, h, Hold::first_order_hold).apply(data.output());
  const Eigen::MatrixXd fu =
      SampledFilter(*bank, h, data.input_hold()).apply(delay_samples(data.input(), input_delay));
  const int l = order.integrators;
  Eigen::MatrixXd x(data.size(), order.n + order.m + 1);
  for (int k = 1; k <= order.n; ++k) x.col(k - 1) = -fy.col(k + l);
  x.rightCols(order.m + 1) = fu.leftCols(order.m + 1);
  return internal::scaled_least_squares(x, fy.col(l)).coefficients;
}

// B / (p^l A) of LSSVF's parameters; throws InvalidArgument naming a coefficient that is not
// finite.
TransferFunction lssvf_model(const Eigen::VectorXd& theta, const SubmodelOrder& order) {
  Eigen::VectorXd a(order.n + 1);
  a(0) = 1.0;
  a.tail(order.n) = theta.head(order.n);
  return TransferFunction(Polynomial::trimmed(theta.tail(order.m + 1)),
                          Polynomial::monomial(order.integrators) * Polynomial::trimmed(a));
}

// The coefficients of mode_from_peak's polynomial, ascending.
Eigen::VectorXd mode_coefficients(const ResonancePeak& peak) {
  const double zeta =
      std::isfinite(peak.damping_ratio) ? std::clamp(peak.damping_ratio, 1e-3, 0.5) : 0.05;
  const double w = peak.frequency / std::sqrt(1.0 - 2.0 * zeta * zeta);  // resonance -> w_n
  Eigen::VectorXd c(3);
  c << 1.0, 2.0 * zeta / w, 1.0 / (w * w);
  return c;
}

}  // namespace

TransferFunction lssvf(const SampledData& data, const SubmodelOrder& order, double bandwidth,
                       int input_delay) {
  const std::optional<Eigen::VectorXd> theta =
      lssvf_parameters(data, order, bandwidth, input_delay);
  require(theta.has_value(), "lssvf: the state-variable filter (1 + p/", bandwidth, ")^",
          order.n + order.integrators, " has no finite realisation; use a larger bandwidth");
  return lssvf_model(*theta, order);
}

Polynomial mode_from_peak(const ResonancePeak& peak) { return Polynomial(mode_coefficients(peak)); }

namespace internal {

std::optional<TransferFunction> lssvf_if_finite(const SampledData& data, const SubmodelOrder& order,
                                                double bandwidth, int input_delay) {
  const std::optional<Eigen::VectorXd> theta =
      lssvf_parameters(data, order, bandwidth, input_delay);
  if (!theta || !theta->allFinite()) return std::nullopt;
  return lssvf_model(*theta, order);
}

std::optional<Polynomial> mode_from_peak_if_finite(const ResonancePeak& peak) {
  Eigen::VectorXd c = mode_coefficients(peak);
  if (!c.allFinite() || c(2) == 0.0) return std::nullopt;
  return Polynomial(std::move(c));
}

std::optional<TransferFunction> frf_peak_start_if_formed(const SampledData& data,
                                                         const SubmodelOrder& order,
                                                         int input_delay, std::string* failure) {
  const int pairs = order.n / 2;
  if (data.size() < 16) return std::nullopt;
  WelchOptions welch;
  welch.segment_length = default_segment_length(data.size());
  const Frf frf = welch_frf(data, welch);
  std::vector<ResonancePeak> peaks;
  if (pairs > 0) {
    PeakOptions options;
    options.max_peaks = pairs;
    peaks = resonance_peaks(frf, options);
    if (static_cast<int>(peaks.size()) < pairs) return std::nullopt;
  }
  const auto fail = [failure](std::string reason) -> std::optional<TransferFunction> {
    if (failure != nullptr) *failure = std::move(reason);
    return std::nullopt;
  };
  std::optional<Polynomial> a = Polynomial{1.0};
  for (const ResonancePeak& peak : peaks) {
    const std::optional<Polynomial> mode = mode_from_peak_if_finite(peak);
    if (mode) a = product_if_finite(*a, *mode);
    if (!mode || !a) {
      return fail(concat("frf_peak_start: the peak at ", peak.frequency,
                         " rad/s gives no finite denominator"));
    }
  }
  if (order.n % 2 == 1) a = product_if_finite(*a, Polynomial{1.0, 1.0 / frf.frequencies(0)});
  if (!a) return fail("frf_peak_start: the peaks give no finite denominator");
  const TransferFunction poles_only(Polynomial{1.0}, Polynomial::monomial(order.integrators) * *a);
  const std::optional<AdditiveModel> grouped =
      grouped_submodels(poles_only, {order}, data, input_delay, failure);
  if (!grouped) return std::nullopt;
  std::optional<TransferFunction> g = transfer_function_if_finite(*grouped);
  if (!g) return fail("frf_peak_start: the start's transfer function overflows");
  return g->with_input_delay(0.0);
}

}  // namespace internal

std::optional<TransferFunction> frf_peak_start(const SampledData& data, const SubmodelOrder& order,
                                               int input_delay) {
  std::string failure;
  std::optional<TransferFunction> start =
      internal::frf_peak_start_if_formed(data, order, input_delay, &failure);
  if (!start && !failure.empty()) throw InvalidArgument(failure);
  return start;
}

namespace {

// Closed loop: `beta` (laid out for `orders`) made a model the controller stabilises, by
// reflecting right-half-plane poles and then halving every numerator while the loop is
// unstable (a direct estimate from closed-loop data leans toward -1/C_d where the noise
// dominates, i.e. toward a loop gain that is too high); none if kStartGainHalvings halvings do
// not do it.
std::optional<Eigen::VectorXd> stabilised(Eigen::VectorXd beta,
                                          const std::vector<SubmodelOrder>& orders,
                                          const DiscreteTransferFunction& controller, double h,
                                          int input_delay) {
  if (!beta.allFinite()) return std::nullopt;
  int at = 0;
  for (const SubmodelOrder& o : orders) {
    if (o.n >= 1) {
      Eigen::VectorXd a(o.n + 1);
      a(0) = 1.0;
      a.tail(o.n) = beta.segment(at, o.n);
      bool reflected = false;
      const Polynomial r = internal::reflect_unstable_roots(Polynomial(a), reflected);
      if (reflected) {
        if (r.degree() != o.n) return std::nullopt;
        for (int k = 1; k <= o.n; ++k) beta(at + k - 1) = r[k];
      }
    }
    at += o.n + o.m + 1;
  }
  for (int halving = 0; halving <= InitializationOptions::kStartGainHalvings; ++halving) {
    if (internal::controller_stabilises(orders, beta, controller, h, input_delay)) return beta;
    at = 0;
    for (const SubmodelOrder& o : orders) {
      beta.segment(at + o.n, o.m + 1) *= 0.5;
      at += o.n + o.m + 1;
    }
  }
  return std::nullopt;
}

// Mean squared output error y - G u of `model` (with the input delay), as the engine computes
// mean_squared_error.
double output_error(const AdditiveModel& model, const SampledData& data) {
  return (data.output() - model_output(model, data.input(), data.sample_time(), data.input_hold()))
             .squaredNorm() /
         data.size();
}

}  // namespace

int InitializationOptions::screening_length(int samples) const {
  if (screening_samples == 0 || samples <= screening_samples) return samples;
  return std::min(samples, std::max({screening_samples, samples / kScreeningFraction, 100}));
}

namespace {

// The piece of `record` the candidates are screened on (screening_length); none: the whole.
std::optional<SampledData> screening_piece(const SampledData& record,
                                           const InitializationOptions& options) {
  const int length = options.screening_length(record.size());
  if (length >= record.size()) return std::nullopt;
  return record.segment(0, length);
}

// initial_transfer_function's closed-loop data: a reference, and the controller at its sample
// time.
void check_start_controller(const SampledData& data, const DiscreteTransferFunction& controller) {
  const double h = data.sample_time();
  require(data.has_reference(),
          "initial_transfer_function: a controller is given but the data has no reference r");
  require(std::abs(controller.sample_time() - h) <= 1e-9 * h,
          "initial_transfer_function: the controller's sample time ", controller.sample_time(),
          " differs from the data's ", h);
}

// Refines one open-loop candidate by SRIVC with `refine` (or judges it as it is) and keeps it
// in `kept` if its output error is below `cost_so_far`.
void refine_open_loop_start(const SampledData& data, const SubmodelOrder& order,
                            const InitializationOptions& options, double delay,
                            RefinedIvOptions& refine, AdditiveModel model, double& cost_so_far,
                            std::optional<TransferFunction>& kept) {
  if (options.refinement_iterations > 0) {
    refine.initial_model = model;
    const EstimationResult r = srivc(data, order, refine);
    if (std::isfinite(r.mean_squared_error) && r.mean_squared_error < cost_so_far) {
      cost_so_far = r.mean_squared_error;
      kept = r.transfer_function.with_input_delay(0.0);
    }
  } else {
    // Judge the (stabilised) model by its output error.
    bool reflected = false;
    const Polynomial a = internal::reflect_unstable_roots(model[0].a, reflected);
    model = AdditiveModel({Submodel{a, model[0].b, order.integrators}}, delay);
    const double cost = output_error(model, data);
    if (std::isfinite(cost) && cost < cost_so_far) {
      cost_so_far = cost;
      kept = model.to_transfer_function().with_input_delay(0.0);
    }
  }
}

// consider(start): the candidate and its refinements (whole SRIVC and CLSRIVC runs) kept if
// they are better; false when a refinement run stopped with InvalidArgument. The refined IV
// engine still ends a run that way on a degenerate iterate, so this is the one catch left here
// (decision 0045): the start itself is formed as a value.
template <typename Consider>
bool refined_candidate(const Consider& consider, const TransferFunction& start) {
  try {
    consider(start);
    return true;
  } catch (const InvalidArgument&) {
    return false;
  }
}

// initial_transfer_function on `data`, the piece already chosen (options validated), as a value:
// none, with the reason in `failure` if given, when no candidate start can be formed.
std::optional<TransferFunction> screened_transfer_function(const SampledData& data,
                                                           const SubmodelOrder& order,
                                                           const InitializationOptions& options,
                                                           std::string* failure) {
  const double h = data.sample_time();
  const DiscreteTransferFunction* controller = options.controller ? &*options.controller : nullptr;
  if (controller != nullptr) check_start_controller(data, *controller);
  const double delay = options.input_delay_samples * h;
  double best_cost = std::numeric_limits<double>::infinity();
  std::optional<TransferFunction> best;
  // Closed loop, when the controller stabilises no candidate: the open-loop choice, so the
  // caller can still say which model the loop failed on.
  double unstabilised_cost = std::numeric_limits<double>::infinity();
  std::optional<TransferFunction> unstabilised;
  const auto keep = [&](const AdditiveModel& model, double cost) {
    if (std::isfinite(cost) && cost < best_cost) {
      best_cost = cost;
      best = model.to_transfer_function().with_input_delay(0.0);
    }
  };
  RefinedIvOptions refine;
  refine.max_iterations = std::max(options.refinement_iterations, 1);
  refine.tolerance = 1e-8;
  refine.input_delay_samples = options.input_delay_samples;
  refine.compute_covariance = false;
  const auto consider_open_loop = [&](const AdditiveModel& model, double& cost_so_far,
                                      std::optional<TransferFunction>& kept) {
    refine_open_loop_start(data, order, options, delay, refine, model, cost_so_far, kept);
  };
  // Closed loop: the candidate made one the controller stabilises, refined by CLSRIVC (whose
  // instrument needs S_uo r, so a stabilised start is what lets it run at all); the refined
  // model is kept only if the controller still stabilises it, else the stabilised start.
  const auto consider_closed_loop = [&](const Eigen::VectorXd& theta) {
    const std::optional<Eigen::VectorXd> start =
        stabilised(theta, {order}, *controller, h, options.input_delay_samples);
    if (!start) return false;
    const AdditiveModel model = AdditiveModel::from_parameters({order}, *start, delay);
    keep(model, output_error(model, data));
    if (options.refinement_iterations > 0) {
      internal::RefinedIvProblem problem;
      problem.records = {&data};
      problem.orders = {order};
      problem.controller = controller;
      problem.unfactored = true;
      problem.name = "clsrivc (start)";
      refine.initial_model = model;  // so the inner run does not look for a start itself
      const EstimationResult r = internal::run_refined_iv(problem, refine);
      if (internal::controller_stabilises({order}, r.parameters, *controller, h,
                                          options.input_delay_samples)) {
        keep(r.model, r.mean_squared_error);
      }
    }
    return true;
  };
  const auto consider = [&](const TransferFunction& start) {
    const Eigen::VectorXd theta = internal::unfactored_parameters(start, order);
    if (!theta.allFinite()) return;
    const AdditiveModel model = AdditiveModel::from_parameters({order}, theta);
    if (controller == nullptr) {
      consider_open_loop(model, best_cost, best);
      return;
    }
    consider_closed_loop(theta);
    // The open-loop refinement of the candidate is a second candidate: SRIVC often moves a
    // poor LSSVF start close to the closed-loop estimate even though its gain is biased.
    std::optional<TransferFunction> refined;
    double refined_cost = std::numeric_limits<double>::infinity();
    consider_open_loop(model, refined_cost, refined);
    if (!refined) return;
    if (!consider_closed_loop(internal::unfactored_parameters(*refined, order)) &&
        refined_cost < unstabilised_cost) {
      unstabilised_cost = refined_cost;
      unstabilised = refined;
    }
  };

  if (options.method != StartMethod::frf) {
    std::vector<double> grid = options.filter_bandwidths;
    const double nyquist = M_PI / h;
    if (grid.empty()) {
      for (double w = nyquist / 128.0; w <= nyquist * 1.0001; w *= 2.0) grid.push_back(w);
    }
    for (double lambda : grid) {
      // A bandwidth that gives a degenerate start is skipped.
      const std::optional<TransferFunction> start =
          internal::lssvf_if_finite(data, order, lambda, options.input_delay_samples);
      if (start) refined_candidate(consider, *start);
    }
  }
  if (options.method != StartMethod::lssvf) {
    // An FRF with too few peaks, or whose peaks give a degenerate start, is not a candidate.
    const std::optional<TransferFunction> start =
        internal::frf_peak_start_if_formed(data, order, options.input_delay_samples);
    const bool found = start.has_value() && refined_candidate(consider, *start);
    if (!found && options.method == StartMethod::frf) {
      if (failure != nullptr) {
        *failure = internal::concat(
            "initial_transfer_function: the record's FRF has fewer resonance ", "peaks than the ",
            order.n / 2, " pole pairs of the structure; use ", "another start (lssvf or a model)");
      }
      return std::nullopt;
    }
  }
  if (!best && unstabilised) return *unstabilised;
  if (!best && failure != nullptr) {
    *failure =
        "initial_transfer_function: no candidate start gave a finite model; give an "
        "initial model";
  }
  return best;
}

}  // namespace

std::optional<TransferFunction> internal::initial_transfer_function_if_formed(
    const SampledData& record, const SubmodelOrder& order, const InitializationOptions& options,
    std::string* failure) {
  options.validate();
  const std::optional<SampledData> piece = screening_piece(record, options);
  return screened_transfer_function(piece ? *piece : record, order, options, failure);
}

TransferFunction initial_transfer_function(const SampledData& record, const SubmodelOrder& order,
                                           const InitializationOptions& options) {
  std::string failure;
  std::optional<TransferFunction> g =
      internal::initial_transfer_function_if_formed(record, order, options, &failure);
  if (!g) throw InvalidArgument(failure);
  return std::move(*g);
}

namespace {

// The failure of a step of grouped_submodels: `reason` in `failure` if given, and none.
std::nullopt_t grouping_failed(std::string* failure, std::string reason) {
  if (failure != nullptr) *failure = std::move(reason);
  return std::nullopt;
}

// g's non-zero poles, unstable ones reflected, one of each pair, slowest first.
std::vector<std::complex<double>> poles_to_group(const Polynomial& den, int nonzero) {
  std::vector<std::complex<double>> poles;
  if (nonzero > 0) {
    const Polynomial reduced(den.coefficients().tail(nonzero + 1));
    const Eigen::VectorXcd r = reduced.roots();
    for (Eigen::Index k = 0; k < r.size(); ++k) {
      std::complex<double> z = r(k);
      if (z.real() > 0.0) z = {-z.real(), z.imag()};
      if (z.imag() >= -1e-9 * std::abs(z)) poles.push_back(z);  // one of each pair
    }
  }
  std::sort(poles.begin(), poles.end(),
            [](const std::complex<double>& a, const std::complex<double>& b) {
              return std::abs(a) < std::abs(b);
            });
  return poles;
}

// Units go to submodels from the slowest up, each to the first listed submodel with room
// for it whole, a real pole preferring a submodel with an odd number of poles left: the
// grouping does not depend on the order the submodels are listed in (a first-order and a
// second-order submodel get the real pole and the pair either way). A pair that fits
// nowhere whole is split into two real poles of its magnitude. The anti-monic denominators;
// none when the poles do not fit or make no finite denominator.
std::optional<std::vector<Polynomial>> grouped_denominators(
    const std::vector<std::complex<double>>& poles, const std::vector<SubmodelOrder>& orders,
    std::string* failure) {
  // Units: a complex pair (two poles) or one real pole.
  std::deque<std::vector<std::complex<double>>> units;
  for (const auto& z : poles) {
    if (std::abs(z.imag()) > 1e-9 * std::abs(z)) {
      units.push_back({z, std::conj(z)});
    } else {
      units.push_back({std::complex<double>(z.real(), 0.0)});
    }
  }
  std::vector<std::vector<std::complex<double>>> assigned(orders.size());
  auto room = [&](size_t i) { return orders[i].n - static_cast<int>(assigned[i].size()); };
  while (!units.empty()) {
    std::vector<std::complex<double>> unit = units.front();
    units.pop_front();
    const int size = static_cast<int>(unit.size());
    std::optional<size_t> chosen;
    for (size_t i = 0; i < orders.size(); ++i) {
      if (room(i) < size) continue;
      const bool preferred = size == 2 || room(i) % 2 == 1;
      if (preferred) {
        chosen = i;
        break;
      }
      if (!chosen) chosen = i;
    }
    if (!chosen) {
      if (size != 2) {
        return grouping_failed(failure, "group_into_submodels: ran out of room for a real pole");
      }
      const double m = -std::abs(unit[0]);
      units.push_front({std::complex<double>(m, 0.0)});
      units.push_front({std::complex<double>(m, 0.0)});
      continue;
    }
    assigned[*chosen].insert(assigned[*chosen].end(), unit.begin(), unit.end());
  }
  std::vector<Polynomial> denominators;
  for (size_t i = 0; i < orders.size(); ++i) {
    const std::vector<std::complex<double>>& mine = assigned[i];
    if (static_cast<int>(mine.size()) != orders[i].n) {
      return grouping_failed(failure, "group_into_submodels: ran out of poles");
    }
    Polynomial a{1.0};
    if (!mine.empty()) {
      Eigen::VectorXcd roots(static_cast<Eigen::Index>(mine.size()));
      for (size_t k = 0; k < mine.size(); ++k) roots(static_cast<Eigen::Index>(k)) = mine[k];
      const std::optional<Polynomial> product =
          internal::polynomial_from_roots(roots, 1.0, failure);
      if (!product) return std::nullopt;
      const std::optional<Polynomial> anti_monic =
          internal::anti_monic_if_finite(*product, failure);
      if (!anti_monic) return std::nullopt;
      a = *anti_monic;
    }
    denominators.push_back(a);
  }
  return denominators;
}

}  // namespace

namespace internal {

std::optional<AdditiveModel> grouped_submodels(const TransferFunction& g,
                                               const std::vector<SubmodelOrder>& orders,
                                               const SampledData& data, int input_delay,
                                               std::string* failure) {
  require(!orders.empty(), "group_into_submodels: the structure has no submodels");
  const Polynomial& den = g.denominator();
  int origin = 0;
  while (origin <= den.degree() && den[origin] == 0.0) ++origin;
  int n_total = 0;
  int l_total = 0;
  for (const SubmodelOrder& o : orders) {
    n_total += o.n;
    l_total += o.integrators;
  }
  const int nonzero = den.degree() - origin;
  if (nonzero != n_total || origin != l_total) {
    return grouping_failed(
        failure,
        concat("group_into_submodels: the model has ", nonzero, " non-zero poles and ", origin,
               " at the origin; the structure asks for ", n_total, " and ", l_total));
  }
  const std::optional<std::vector<Polynomial>> denominators =
      grouped_denominators(poles_to_group(den, nonzero), orders, failure);
  if (!denominators) return std::nullopt;
  int columns = 0;
  for (const SubmodelOrder& o : orders) columns += o.m + 1;
  const Eigen::VectorXd u = delay_samples(data.input(), input_delay);
  const double h = data.sample_time();
  // Numerators by output-error least squares with the denominators fixed.
  Eigen::MatrixXd x(data.size(), columns);
  int at = 0;
  for (size_t i = 0; i < orders.size(); ++i) {
    const Polynomial d = Polynomial::monomial(orders[i].integrators) * (*denominators)[i];
    const std::optional<FilterRealization> bank = finite_derivative_filters(d);
    if (!bank) {
      return grouping_failed(
          failure, d.degree() < 1 ? concat("derivative_filters: the denominator must have "
                                           "degree >= 1, got ",
                                           d.degree())
                                  : std::string("FilterRealization: an entry is not finite"));
    }
    const Eigen::MatrixXd f = SampledFilter(*bank, h, data.input_hold()).apply(u);
    x.middleCols(at, orders[i].m + 1) = f.leftCols(orders[i].m + 1);
    at += orders[i].m + 1;
  }
  const Eigen::VectorXd b = scaled_least_squares(x, data.output()).coefficients;
  Eigen::VectorXd beta(n_total + columns);
  int pos = 0;
  at = 0;
  for (size_t i = 0; i < orders.size(); ++i) {
    for (int k = 1; k <= orders[i].n; ++k) beta(pos++) = (*denominators)[i][k];
    for (int k = 0; k <= orders[i].m; ++k) beta(pos++) = b(at++);
  }
  if (!beta.allFinite()) return grouping_failed(failure, "parameter vector has a non-finite entry");
  return AdditiveModel::from_parameters(orders, beta, input_delay * h);
}

}  // namespace internal

AdditiveModel group_into_submodels(const TransferFunction& g,
                                   const std::vector<SubmodelOrder>& orders,
                                   const SampledData& data, int input_delay) {
  std::string failure;
  std::optional<AdditiveModel> model =
      internal::grouped_submodels(g, orders, data, input_delay, &failure);
  if (!model) throw InvalidArgument(failure);
  return std::move(*model);
}

AdditiveModel initial_additive_model(const SampledData& record,
                                     const std::vector<SubmodelOrder>& orders,
                                     const InitializationOptions& options) {
  return additive_model_from_start(
      initial_transfer_function(record, unfactored_order(orders), options), record, orders,
      options);
}

std::optional<AdditiveModel> internal::additive_model_from_start_if_formed(
    const TransferFunction& g, const SampledData& record, const std::vector<SubmodelOrder>& orders,
    const InitializationOptions& options, std::string* failure) {
  options.validate();
  const SubmodelOrder total = unfactored_order(orders);
  // The numerators are fitted on the piece the start was screened on.
  const std::optional<SampledData> piece = screening_piece(record, options);
  const SampledData& data = piece ? *piece : record;
  if (!options.controller) {
    return internal::grouped_submodels(g, orders, data, options.input_delay_samples, failure);
  }
  // Closed loop: the numerators are fitted to g's own response to u rather than to y, so the
  // grouped model stays the stabilised start g (refitting them to y would bring back the
  // pull toward -1/C_d the start was screened against); the gain is halved if needed.
  const double h = data.sample_time();
  const AdditiveModel unfactored = AdditiveModel::from_parameters(
      {total}, internal::unfactored_parameters(g, total), options.input_delay_samples * h);
  const SampledData own(h, data.input(),
                        model_output(unfactored, data.input(), h, data.input_hold()));
  const std::optional<AdditiveModel> grouped = internal::grouped_submodels(
      g, orders, own.with_input_hold(data.input_hold()), options.input_delay_samples, failure);
  if (!grouped) return std::nullopt;
  const std::optional<Eigen::VectorXd> beta = stabilised(
      grouped->parameters(), orders, *options.controller, h, options.input_delay_samples);
  return beta ? grouped->with_parameters(*beta) : *grouped;
}

AdditiveModel additive_model_from_start(const TransferFunction& g, const SampledData& record,
                                        const std::vector<SubmodelOrder>& orders,
                                        const InitializationOptions& options) {
  std::string failure;
  std::optional<AdditiveModel> model =
      internal::additive_model_from_start_if_formed(g, record, orders, options, &failure);
  if (!model) throw InvalidArgument(failure);
  return std::move(*model);
}

}  // namespace ctid
