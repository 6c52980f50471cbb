// Where the parameters of a MimoAdditiveModel sit, shared by the time-domain (mimo_srivc,
// refined_iv) and the FRF-matrix (frf_matrix_fit, frf_fit) estimators, by the modes computed
// from either (mimo_modes) and by the layout of their covariance: every submodel's a_i1..a_in
// in one block, then per output j its numerator coefficients (submodel i, input k, power r)
// and D[j, .] last. Private to the estimator modules (decision 0045).
#pragma once

#include <cstddef>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/error.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/polynomial.h"

namespace ctid::internal {

struct MimoLayout {
  std::vector<SubmodelOrder> orders;
  int inputs = 0;
  int outputs = 0;
  std::vector<int> a_at;  // first a-entry of submodel i
  std::vector<int> u_at;  // first numerator column of submodel i (input 0)
  int a_count = 0;
  int u_count = 0;  // numerator columns (and D) of one output
  bool direct = false;
  int d_at = 0;  // first column of the direct term (input 0)
  // Time domain only: the fraction of a sample by which each input is delayed after its whole
  // samples were shifted into the record (mimo_srivc's input_delays); empty: none.
  std::vector<double> input_fractions;
  // Time domain only (InitialConditions::estimate): every submodel's n_i + l_i free-response
  // columns, appended after the numerators and D; the same columns for every output, each
  // output with its own coefficients. free_at[i] is submodel i's first; free_count counts them.
  std::vector<int> free_at;
  int free_count = 0;

  MimoLayout(std::vector<SubmodelOrder> o, int n_u, int n_y, bool with_direct)
      : orders(std::move(o)), inputs(n_u), outputs(n_y), direct(with_direct) {
    for (const SubmodelOrder& s : orders) {
      a_at.push_back(a_count);
      u_at.push_back(u_count);
      a_count += s.n;
      u_count += inputs * (s.m + 1);
    }
    d_at = u_count;
    if (direct) u_count += inputs;
  }
  /// Appends the free-response columns (see free_at).
  void add_free_responses() {
    for (const SubmodelOrder& s : orders) {
      free_at.push_back(u_count);
      u_count += s.n + s.integrators;
      free_count += s.n + s.integrators;
    }
  }
  /// Columns of one output that belong to the model (numerators and D, not free responses).
  int model_columns() const { return u_count - free_count; }
  int states(int i) const {
    return orders[static_cast<std::size_t>(i)].n + orders[static_cast<std::size_t>(i)].integrators;
  }
  int size() const { return static_cast<int>(orders.size()); }
  /// Right-hand sides of (29): one per submodel, and one for the direct term.
  int columns() const { return size() + (direct ? 1 : 0); }
  int parameters() const { return a_count + outputs * u_count; }
  /// Numerator column of submodel i, input k, power r.
  int u_column(int i, int k, int r) const {
    return u_at[static_cast<std::size_t>(i)] + k * (orders[static_cast<std::size_t>(i)].m + 1) + r;
  }
  /// Parameters one channel's response depends on: its submodels' numerators and D.
  int channel_columns() const {
    int c = direct ? 1 : 0;
    for (const SubmodelOrder& s : orders) c += s.m + 1;
    return c;
  }
  /// Input k's delay fraction in [0, 1).
  double input_fraction(int k) const {
    return input_fractions.empty() ? 0.0 : input_fractions[static_cast<std::size_t>(k)];
  }
  /// Index in the covariance's layout of a_iq and of output j's numerator column.
  int a_index(int i, int q) const { return a_at[static_cast<std::size_t>(i)] + q - 1; }
  int b_index(int j, int column) const { return a_count + j * u_count + column; }
};

/// Throws InvalidArgument (message from `who`) unless `start` has the layout's channels (those
/// of `data`, e.g. "the data" or "the FRF"), submodel count and pole counts.
inline void check_initial_model(const MimoLayout& layout, const MimoAdditiveModel& start,
                                std::string_view who, std::string_view data) {
  require(start.inputs() == layout.inputs && start.outputs() == layout.outputs, who,
          ": the initial model is ", start.outputs(), " x ", start.inputs(), " but ", data, " is ",
          layout.outputs, " x ", layout.inputs, " (outputs x inputs)");
  require(start.size() == layout.size(), who, ": the initial model has ", start.size(),
          " submodels; the structure has ", layout.size());
  for (int i = 0; i < layout.size(); ++i) {
    const int n = layout.orders[static_cast<std::size_t>(i)].n;
    require(start[i].a.degree() == n, who, ": submodel ", i + 1, " of the initial model has ",
            start[i].a.degree(), " poles; the structure asks for ", n);
    const int l = layout.orders[static_cast<std::size_t>(i)].integrators;
    require(start[i].integrators == l, who, ": submodel ", i + 1, " of the initial model has ",
            start[i].integrators, " integrators; the structure asks for ", l);
  }
}

/// The model of denominators `a` whose numerators and D are the coefficients `b` of the
/// numerator columns (at least model_columns() x outputs, one column per output; rows past the
/// model's columns are not read). A numerator estimated as exactly zero is trimmed.
MimoAdditiveModel model_from_columns(const MimoLayout& layout, const std::vector<Polynomial>& a,
                                     const Eigen::MatrixXd& b);

}  // namespace ctid::internal
