// The rank-one residue refit of a mimo_srivc estimate (MimoRefinedIvOptions::rank_one_residues),
// as named phases: the modes and the basis, the start, the alternating sweeps, the model.
#include "ctid/refined_iv/mimo_srivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/scaled_least_squares.h"
#include "internal/mimo_srivc_parts.h"
#include "internal/refined_iv_engine.h"

namespace ctid::mimo_srivc_parts {

namespace {

// A mode of the rank-one fit: its shape psi and participations L, and where its columns sit in
// the basis F.
struct RankOneMode {
  int submodel;
  bool complex;  // m_i = 1
  std::complex<double> pole;
  int at;  // first basis column: e_0..e_{nu-1}, then f_0..f_{nu-1} when complex
  Eigen::VectorXcd psi;
  Eigen::VectorXcd l;
};

// The rank-one fit's least-squares problem in the QR coordinates of its basis F = [e, f of
// every mode | the other columns]: F = Q R S (S the column norms), r = R S maps coefficients of
// F to the QR coordinates, q_y = Q^T y.
struct RankOneProblem {
  int nu = 0;
  int ny = 0;
  int p = 0;  // the modes' columns
  int p_all = 0;
  int n_other = 0;
  std::vector<RankOneMode> modes;
  std::vector<int> others;  // the general columns of the model's layout
  Eigen::MatrixXd r;
  Eigen::MatrixXd q_y;
};

// The modes that can be restricted (complex pairs with m_i <= 1) and the other columns.
void find_rank_one_modes(const Layout& layout, const MimoAdditiveModel& general,
                         RankOneProblem& f) {
  const int nu = f.nu;
  std::vector<bool> in_mode(static_cast<size_t>(layout.u_count), false);
  int p = 0;
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const Polynomial& a = general[i].a;
    if (o.n != 2 || o.integrators > 0 || o.m > 1 || !(a[1] * a[1] < 4.0 * a[2])) continue;
    f.modes.push_back({i, o.m == 1, upper_pole(a[1], a[2]), p, {}, {}});
    p += o.m == 1 ? 2 * nu : nu;
    for (int k = 0; k < nu; ++k) {
      for (int r = 0; r <= o.m; ++r) in_mode[static_cast<size_t>(layout.u_column(i, k, r))] = true;
    }
  }
  for (int c = 0; c < layout.u_count; ++c) {
    if (!in_mode[static_cast<size_t>(c)]) f.others.push_back(c);
  }
  f.p = p;
}

// The basis F = [e, f of every mode | the other columns] and its thin QR.
void rank_one_basis(const Layout& layout, const MimoData& data, const Eigen::MatrixXd& u,
                    RankOneProblem& f) {
  const int nu = f.nu;
  const int p = f.p;
  Eigen::MatrixXd basis(data.size(), f.p_all);
  for (const RankOneMode& m : f.modes) {
    for (int k = 0; k < nu; ++k) {
      const auto e = u.col(layout.u_column(m.submodel, k, 0));
      basis.col(m.at + k) = e;
      if (m.complex) {
        basis.col(m.at + nu + k) =
            -(u.col(layout.u_column(m.submodel, k, 1)) - m.pole.real() * e) / m.pole.imag();
      }
    }
  }
  for (int c = 0; c < f.n_other; ++c) basis.col(p + c) = u.col(f.others[static_cast<size_t>(c)]);
  const ScaledQr qr = scaled_thin_qr(basis);
  // F = Q R S (S the column norms): R S maps coefficients of F to the QR coordinates, q_y = Q^T y.
  f.r = qr.r * qr.scale.asDiagonal();
  f.q_y = qr.q.transpose() * data.outputs();
}

// Start: the principal singular pair of each mode's c = A'(s) Res matrix.
void start_rank_one_shapes(const MimoAdditiveModel& general, RankOneProblem& f) {
  for (RankOneMode& m : f.modes) {
    Eigen::MatrixXcd c(f.ny, f.nu);
    for (int j = 0; j < f.ny; ++j) {
      for (int k = 0; k < f.nu; ++k) {
        const Polynomial& b = general.numerator(m.submodel, j, k);
        std::complex<double> value = 0.0;
        for (int q = b.degree(); q >= 0; --q) value = value * m.pole + b[q];
        c(j, k) = value;
      }
    }
    if (!m.complex) c = c.real().cast<std::complex<double>>();
    const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(c, Eigen::ComputeThinU | Eigen::ComputeThinV);
    m.psi = svd.matrixU().col(0) * svd.singularValues()(0);
    m.l = svd.matrixV().col(0).conjugate();
    if (!m.complex) {
      // A real matrix's singular vectors may carry a common phase: take it out.
      Eigen::Index big = 0;
      m.psi.cwiseAbs().maxCoeff(&big);
      const std::complex<double> phase = m.psi(big) / std::abs(m.psi(big));
      m.psi = (m.psi / phase).real().cast<std::complex<double>>();
      m.l = (m.l * phase).real().cast<std::complex<double>>();
    }
  }
}

// Coefficients of output j in F's columns for given shapes and participations.
Eigen::VectorXd rank_one_theta(const RankOneProblem& f, int j,
                               const Eigen::VectorXd& general_part) {
  const int nu = f.nu;
  Eigen::VectorXd theta(f.p_all);
  for (const RankOneMode& m : f.modes) {
    for (int k = 0; k < nu; ++k) {
      const std::complex<double> c = m.psi(j) * m.l(k);
      theta(m.at + k) = c.real();
      if (m.complex) theta(m.at + nu + k) = -c.imag();
    }
  }
  theta.tail(f.n_other) = general_part;
  return theta;
}

// Shapes (and the other columns), output by output: theta_j = T(L) [Re psi, Im psi, other].
void fit_rank_one_shapes(RankOneProblem& f, Eigen::MatrixXd& other) {
  const int nu = f.nu;
  const int ny = f.ny;
  const int n_other = f.n_other;
  int q_cols = n_other;
  for (const RankOneMode& m : f.modes) q_cols += m.complex ? 2 : 1;
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(f.p_all, q_cols);
  int col = 0;
  for (const RankOneMode& m : f.modes) {
    for (int k = 0; k < nu; ++k) {
      // Re c = Re psi Re L - Im psi Im L; -Im c = -(Re psi Im L + Im psi Re L).
      t(m.at + k, col) = m.l(k).real();
      if (m.complex) {
        t(m.at + k, col + 1) = -m.l(k).imag();
        t(m.at + nu + k, col) = -m.l(k).imag();
        t(m.at + nu + k, col + 1) = -m.l(k).real();
      }
    }
    col += m.complex ? 2 : 1;
  }
  for (int c = 0; c < n_other; ++c) t(f.p + c, col + c) = 1.0;
  const Eigen::MatrixXd shapes = (f.r * t).colPivHouseholderQr().solve(f.q_y);
  col = 0;
  for (RankOneMode& m : f.modes) {
    for (int j = 0; j < ny; ++j) {
      m.psi(j) = m.complex ? std::complex<double>(shapes(col, j), shapes(col + 1, j))
                           : std::complex<double>(shapes(col, j), 0.0);
    }
    col += m.complex ? 2 : 1;
  }
  other = shapes.bottomRows(n_other);
}

// Participations, every output together: theta_j = S(psi_j) lambda + [0; other_j]; then each
// shape scaled to unit length (the product psi L' is what the model holds).
void fit_rank_one_participations(RankOneProblem& f, const Eigen::MatrixXd& other) {
  const int nu = f.nu;
  const int ny = f.ny;
  const int p_all = f.p_all;
  const Eigen::MatrixXd& r = f.r;
  int l_cols = 0;
  for (const RankOneMode& m : f.modes) l_cols += m.complex ? 2 * nu : nu;
  Eigen::MatrixXd stacked(static_cast<Eigen::Index>(ny) * p_all, l_cols);
  Eigen::VectorXd target(static_cast<Eigen::Index>(ny) * p_all);
  for (int j = 0; j < ny; ++j) {
    Eigen::MatrixXd s_j = Eigen::MatrixXd::Zero(p_all, l_cols);
    int at = 0;
    for (const RankOneMode& m : f.modes) {
      const double re = m.psi(j).real();
      const double im = m.psi(j).imag();
      for (int k = 0; k < nu; ++k) {
        if (m.complex) {
          // lambda = [Re L_0..Re L_{nu-1}, Im L_0..Im L_{nu-1}] of this mode.
          s_j(m.at + k, at + k) = re;
          s_j(m.at + k, at + nu + k) = -im;
          s_j(m.at + nu + k, at + k) = -im;
          s_j(m.at + nu + k, at + nu + k) = -re;
        } else {
          s_j(m.at + k, at + k) = re;
        }
      }
      at += m.complex ? 2 * nu : nu;
    }
    Eigen::VectorXd fixed = Eigen::VectorXd::Zero(p_all);
    fixed.tail(f.n_other) = other.col(j);
    stacked.middleRows(static_cast<Eigen::Index>(j) * p_all, p_all) = r * s_j;
    target.segment(static_cast<Eigen::Index>(j) * p_all, p_all) = f.q_y.col(j) - r * fixed;
  }
  const Eigen::VectorXd lambda = stacked.colPivHouseholderQr().solve(target);
  int at = 0;
  for (RankOneMode& m : f.modes) {
    for (int k = 0; k < nu; ++k) {
      m.l(k) = m.complex ? std::complex<double>(lambda(at + k), lambda(at + nu + k))
                         : std::complex<double>(lambda(at + k), 0.0);
    }
    at += m.complex ? 2 * nu : nu;
    // Scale: psi of unit length (the product psi L' is what the model holds).
    const double norm = m.psi.norm();
    if (norm > 0.0) {
      m.psi /= norm;
      m.l *= norm;
    }
  }
}

// The model: each mode's numerators from c = psi L', the other columns as fitted.
Iterate rank_one_model(const Layout& layout, const MimoAdditiveModel& general,
                       const RankOneProblem& f, const Eigen::MatrixXd& other) {
  const int nu = f.nu;
  const int ny = f.ny;
  Eigen::MatrixXd b(layout.u_count, ny);
  for (int c = 0; c < f.n_other; ++c) b.row(f.others[static_cast<size_t>(c)]) = other.row(c);
  for (const RankOneMode& m : f.modes) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nu; ++k) {
        const std::complex<double> c = m.psi(j) * m.l(k);
        const double n1 = m.complex ? c.imag() / m.pole.imag() : 0.0;
        b(layout.u_column(m.submodel, k, 0), j) = c.real() - m.pole.real() * n1;
        if (m.complex) b(layout.u_column(m.submodel, k, 1), j) = n1;
      }
    }
  }
  return {model_from_columns(layout, denominators(general), b)
              .with_input_delays(general.input_delays()),
          b.bottomRows(layout.free_count)};
}

}  // namespace

// The rank-one fit (see RankOneFit): the modes and the basis, the start from each residue
// matrix's principal singular pair, alternating sweeps, then the model. Free-response
// columns stay general too.
RankOneFit rank_one_residues(const Layout& layout, const MimoData& data, const Iterate& start) {
  const MimoAdditiveModel& general = start.model;
  RankOneProblem f;
  f.nu = layout.inputs;
  f.ny = layout.outputs;
  const Eigen::MatrixXd u = numerator_regressors(layout, data, denominators(general));
  find_rank_one_modes(layout, general, f);
  if (f.modes.empty()) return {start, 0, 0};
  const int n_modes = static_cast<int>(f.modes.size());
  f.n_other = static_cast<int>(f.others.size());
  f.p_all = f.p + f.n_other;
  rank_one_basis(layout, data, u, f);
  start_rank_one_shapes(general, f);

  // Alternating least squares: shapes, then participations, until the cost stops falling.
  Eigen::MatrixXd other(f.n_other, f.ny);  // the general columns' coefficients, per output
  double cost = std::numeric_limits<double>::infinity();
  int iteration = 0;
  constexpr int kMaxSweeps = 2000;
  for (iteration = 1; iteration <= kMaxSweeps; ++iteration) {
    fit_rank_one_shapes(f, other);
    fit_rank_one_participations(f, other);
    double next = 0.0;
    for (int j = 0; j < f.ny; ++j) {
      next += (f.q_y.col(j) - f.r * rank_one_theta(f, j, other.col(j))).squaredNorm();
    }
    const bool done = !(next < cost * (1.0 - 1e-13)) && iteration > 1;
    cost = next;
    if (done || !std::isfinite(next)) break;
  }
  return {rank_one_model(layout, general, f, other), iteration, n_modes};
}

}  // namespace ctid::mimo_srivc_parts
