// Mode counts of a record of several inputs and outputs, fitted and scored (decision 0064;
// mimo_structure_scan.h).
#include "ctid/identification/mimo_structure_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/parallel.h"
#include "ctid/estimation/validation.h"

namespace ctid {
namespace mimo_scan_detail {  // named: the module builds as one unit

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Mean over the outputs of (1 - fit/100)^2: each output's squared error over its variation.
double relative_error(const Eigen::VectorXd& fit) {
  if (fit.size() == 0) return kNan;
  return (1.0 - fit.array() / 100.0).square().mean();
}

// One count's fit, scored; its modes go to `modes` (empty when the fit threw).
MimoStructureFit fit_count(const MimoData& data, const MimoData& estimation, int count,
                           const MimoStructureScanOptions& options, int held_out,
                           std::vector<MimoMode>& modes) {
  MimoStructureFit fit;
  fit.modes = count;
  fit.validation_error = kNan;
  try {
    const std::vector<SubmodelOrder> orders(static_cast<std::size_t>(count),
                                            SubmodelOrder{2, 1, 0});
    const MimoEstimationResult r = identify(estimation, orders, options.identification);
    static_cast<Outcome&>(fit) = r;
    fit.message = r.brief_report();  // the one-line report, not the bare message
    fit.estimation_fit = r.fit_percent;
    modes = r.modes;
    if (!r.model) {
      fit.reasons.push_back("no model was computed");
      return fit;
    }
    fit.reasons = r.verdict.reasons;
    fit.usable = r.verdict.usable;
    if (held_out > 0) {
      ValidationOptions scored;  // from rest over the whole record, scored on the held-out end
      scored.window_start = data.start_time() + estimation.size() * data.sample_time();
      fit.validation_fit = validate_model(*r.model, data, scored).fit_percent;
    } else {
      fit.validation_fit = r.fit_percent;
    }
    fit.validation_error = relative_error(fit.validation_fit);
    if (!std::isfinite(fit.validation_error)) {
      fit.usable = false;
      fit.reasons.push_back("the held-out fit is not finite");
    }
  } catch (const InvalidArgument& e) {
    fit.termination = Termination::not_run;
    fit.message = e.what();
    fit.reasons = {e.what()};
    fit.usable = false;
  }
  return fit;
}

// A count that fits the estimation data worse, by more than `tolerance` (relative), than a
// usable fit with fewer modes stopped short of its optimum (its model set contains the other's).
void judge_against_fewer_modes(std::vector<MimoStructureFit>& fits, double tolerance) {
  for (MimoStructureFit& fit : fits) {
    if (!fit.usable) continue;
    const double own = relative_error(fit.estimation_fit);
    for (const MimoStructureFit& fewer : fits) {
      if (!fewer.usable || fewer.modes >= fit.modes) continue;
      const double other = relative_error(fewer.estimation_fit);
      if (own > other * (1.0 + tolerance)) {
        fit.usable = false;
        fit.reasons.push_back(internal::concat(
            "it fits the estimation data worse than the usable fit of ", fewer.modes,
            " mode(s), whose models it contains: the iteration stopped short of its optimum"));
        break;
      }
    }
  }
}

// The fewest modes whose held-out error is within `tolerance` of the best usable one's.
void recommend(MimoStructureScanResult& result, double tolerance) {
  double best = std::numeric_limits<double>::infinity();
  for (const MimoStructureFit& fit : result.fits) {
    if (fit.usable) best = std::min(best, fit.validation_error);
  }
  for (std::size_t i = 0; i < result.fits.size(); ++i) {
    const MimoStructureFit& fit = result.fits[i];
    if (!fit.usable || !(fit.validation_error <= best * (1.0 + tolerance))) continue;
    if (result.recommended < 0 ||
        fit.modes < result.fits[static_cast<std::size_t>(result.recommended)].modes) {
      result.recommended = static_cast<int>(i);
    }
  }
  const std::string where = result.validation_samples > 0 ? "held-out" : "estimation";
  result.rule = result.recommended < 0
                    ? "no mode count gave a usable fit"
                    : "fewest modes among the usable fits whose " + where +
                          " error (mean over the outputs of (1 - fit/100)^2) is within " +
                          format_significant(100.0 * tolerance, 2) + " % of the best";
}

// Every mode of each fit against the modes of the fit before it in the list.
std::vector<StabilisationPoint> stabilisation_diagram(
    const std::vector<MimoStructureFit>& fits, const std::vector<std::vector<MimoMode>>& modes,
    const MimoStructureScanOptions& options) {
  std::vector<StabilisationPoint> points;
  const std::vector<MimoMode> none;
  for (std::size_t i = 0; i < fits.size(); ++i) {
    const std::vector<MimoMode>& previous = i == 0 ? none : modes[i - 1];
    for (const MimoMode& m : modes[i]) {
      StabilisationPoint point;
      point.fit = static_cast<int>(i);
      point.order = 2 * fits[i].modes;
      point.frequency = m.natural_frequency;
      point.damping_ratio = m.damping_ratio;
      point.stable_pole = m.damping_ratio > 0.0;
      for (const MimoMode& q : previous) {
        const double w = q.natural_frequency;
        if (std::abs(point.frequency - w) <= options.frequency_tolerance * w) {
          point.stable_frequency = true;
          if (std::abs(point.damping_ratio - q.damping_ratio) <=
              options.damping_tolerance * std::abs(q.damping_ratio)) {
            point.stable_damping = true;
          }
        }
      }
      points.push_back(point);
    }
  }
  return points;
}

}  // namespace mimo_scan_detail

MimoStructureScanResult scan_mimo_modes(const MimoData& data, const std::vector<int>& mode_counts,
                                        const MimoStructureScanOptions& options,
                                        const std::function<void(int, int)>& progress) {
  namespace d = mimo_scan_detail;
  options.validate();
  require(!mode_counts.empty(), "scan_mimo_modes: no mode count given");
  std::set<int> seen;
  for (const int k : mode_counts) {
    require(k >= 1, "scan_mimo_modes: a mode count is ", k, "; each must be at least 1");
    require(seen.insert(k).second, "scan_mimo_modes: the mode count ", k, " is given twice");
  }
  const int total = data.size();
  const int held_out = static_cast<int>(std::floor(options.validation_fraction * total));
  const int fitted = total - held_out;
  require(fitted >= 8 && (options.validation_fraction == 0.0 || held_out >= 8),
          "scan_mimo_modes: too few samples: ", total, " samples split into ", fitted,
          " fitted and ", held_out,
          " held out (validation_fraction = ", options.validation_fraction,
          "); each part needs at least 8");
  const MimoData estimation = data.segment(0, fitted);
  MimoStructureScanResult result;
  result.estimation_samples = fitted;
  result.validation_samples = held_out;
  result.fits.resize(mode_counts.size());
  std::vector<std::vector<MimoMode>> modes(mode_counts.size());
  std::mutex progress_mutex;
  int done = 0;
  parallel_for(static_cast<int>(mode_counts.size()), 0, [&](int index) {
    const auto slot = static_cast<std::size_t>(index);
    result.fits[slot] =
        d::fit_count(data, estimation, mode_counts[slot], options, held_out, modes[slot]);
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      progress(++done, static_cast<int>(mode_counts.size()));
    }
  });
  const double noise_tolerance = 2.0 * std::sqrt(2.0 / (held_out > 0 ? held_out : fitted));
  d::judge_against_fewer_modes(result.fits, noise_tolerance);
  d::recommend(result, options.error_tolerance.value_or(noise_tolerance));
  result.stabilisation = d::stabilisation_diagram(result.fits, modes, options);
  return result;
}

}  // namespace ctid
