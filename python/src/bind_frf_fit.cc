// Python bindings of the modal model fitted to a measured FRF matrix (frf_fit/frf_matrix_fit.h,
// reached through its front door identification/frf_matrix.h) and of the FRF-matrix files it
// reads (io/mimo_frf_file.h, io/uff58.h): ctid.mimo_frf builds a MimoFrf from NumPy arrays,
// ctid.frf_matrix_fit fits it (identify(MimoFrf, ...), as `ctid fit-frf`), ctid.read_mimo_frf
// reads a CSV table or a universal file (dataset 58). No numerics here.
#include <complex>
#include <filesystem>
#include <string>
#include <vector>

#include <pybind11/stl/filesystem.h>

#include "common.h"
#include "ctid/core/error.h"
#include "ctid/identification/frf_matrix.h"
#include "ctid/io/csv.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/uff58.h"
#include "fields.h"

namespace ctid::python {

namespace {

using ComplexArray = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

MimoFrf mimo_frf(const Eigen::VectorXd& frequencies, const ComplexArray& response,
                 const std::optional<RealArray>& variance,
                 std::optional<std::vector<std::string>> input_names,
                 std::optional<std::vector<std::string>> output_names) {
  require(response.ndim() == 3, "mimo_frf: response has ", response.ndim(),
          " dimensions; it must be (lines, outputs, inputs)");
  const auto lines = response.shape(0);
  const auto n_y = response.shape(1);
  const auto n_u = response.shape(2);
  require(lines == frequencies.size(), "mimo_frf: ", frequencies.size(), " frequencies but ", lines,
          " response matrices");
  MimoFrf frf;
  frf.frequencies = frequencies;
  const auto r = response.unchecked<3>();
  for (py::ssize_t l = 0; l < lines; ++l) {
    Eigen::MatrixXcd h(n_y, n_u);
    for (py::ssize_t j = 0; j < n_y; ++j) {
      for (py::ssize_t k = 0; k < n_u; ++k) h(j, k) = r(l, j, k);
    }
    frf.response.push_back(std::move(h));
  }
  if (variance) {
    require(variance->ndim() == 3 && variance->shape(0) == lines && variance->shape(1) == n_y &&
                variance->shape(2) == n_u,
            "mimo_frf: variance must have the response's shape (", lines, ", ", n_y, ", ", n_u,
            ")");
    const auto v = variance->unchecked<3>();
    for (py::ssize_t l = 0; l < lines; ++l) {
      Eigen::MatrixXd m(n_y, n_u);
      for (py::ssize_t j = 0; j < n_y; ++j) {
        for (py::ssize_t k = 0; k < n_u; ++k) m(j, k) = v(l, j, k);
      }
      frf.variance.push_back(std::move(m));
    }
  }
  const auto names = [](std::optional<std::vector<std::string>> given, py::ssize_t count,
                        const char* prefix, const char* what) {
    if (!given) {
      std::vector<std::string> made;
      for (py::ssize_t i = 0; i < count; ++i) made.push_back(prefix + std::to_string(i + 1));
      return made;
    }
    require(static_cast<py::ssize_t>(given->size()) == count, "mimo_frf: ", given->size(), " ",
            what, " names for ", count, " ", what, "s");
    return *given;
  };
  frf.input_names = names(std::move(input_names), n_u, "u", "input");
  frf.output_names = names(std::move(output_names), n_y, "y", "output");
  return frf;
}

py::array_t<std::complex<double>> response_array(const std::vector<Eigen::MatrixXcd>& g, int n_y,
                                                 int n_u) {
  py::array_t<std::complex<double>> out({static_cast<py::ssize_t>(g.size()),
                                         static_cast<py::ssize_t>(n_y),
                                         static_cast<py::ssize_t>(n_u)});
  auto view = out.mutable_unchecked<3>();
  for (std::size_t l = 0; l < g.size(); ++l) {
    for (int j = 0; j < n_y; ++j) {
      for (int k = 0; k < n_u; ++k) view(static_cast<py::ssize_t>(l), j, k) = g[l](j, k);
    }
  }
  return out;
}

}  // namespace

void bind_frf_fit(py::module_& m) {
  bind_enum<FrfWeighting>(m, "FrfWeighting", "Weighting of the FRF entries in frf_matrix_fit.");
  bind_options<FrfMatrixFitOptions>(m, "Options of frf_matrix_fit.");
  bind_result<FrfMatrixFitResult>(
      m, "What frf_matrix_fit found: the model, per-channel fits, the verdict and the modes.")
      .def("converged", &FrfMatrixFitResult::converged, "termination == converged.");
  m.def("mimo_frf", &mimo_frf, py::arg("frequencies"), py::arg("response"),
        py::arg("variance") = py::none(), py::arg("input_names") = py::none(),
        py::arg("output_names") = py::none(),
        "A MimoFrf from arrays: frequencies [rad/s] (lines), response (lines, outputs, "
        "inputs) complex, optional variance of the same shape; names default to u1.., y1...");
  m.def(
      "frf_matrix_fit",
      [](const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
         const std::optional<MimoAdditiveModel>& initial_model,
         const std::optional<FrfMatrixFitOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<FrfMatrixFitOptions>("frf_matrix_fit", options, kwargs);
        py::gil_scoped_release release;
        return identify(frf, orders, FrfIdentificationOptions{o, initial_model});
      },
      py::arg("frf"), py::arg("orders"), py::arg("initial_model") = py::none(),
      py::arg("options") = py::none(),
      "A modal model with poles shared by every channel fitted to an FRF matrix (vector-fitting "
      "start, numerators by least squares, Levenberg-Marquardt); options are one "
      "FrfMatrixFitOptions or its fields as keywords.");
  m.def(
      "mimo_frequency_response",
      [](const MimoAdditiveModel& model, const Eigen::VectorXd& frequencies) {
        return response_array(mimo_frequency_response(model, frequencies), model.outputs(),
                              model.inputs());
      },
      py::arg("model"), py::arg("frequencies"),
      "G(j w) of a MimoAdditiveModel as a complex array (lines, outputs, inputs).");
  m.def(
      "read_mimo_frf", [](const std::filesystem::path& path) { return io::read_mimo_frf(path); },
      py::arg("path"),
      "An FRF matrix from a CSV table (ctid frf -o X.csv) or a universal file (.uff/.unv, "
      "dataset 58).");
  m.def(
      "write_uff58",
      [](const std::filesystem::path& path, const MimoFrf& frf, bool overwrite) {
        io::write_uff58(path, frf, overwrite ? io::Overwrite::yes : io::Overwrite::no);
      },
      py::arg("path"), py::arg("frf"), py::arg("overwrite") = false,
      "Writes the FRF matrix as universal file dataset 58 records (one per output/input).");
  m.def(
      "write_mimo_frf_csv",
      [](const std::filesystem::path& path, const MimoFrf& frf, bool overwrite) {
        io::write_csv(path, io::mimo_frf_table(frf),
                      overwrite ? io::Overwrite::yes : io::Overwrite::no);
      },
      py::arg("path"), py::arg("frf"), py::arg("overwrite") = false,
      "Writes the FRF matrix as the CSV table ctid frf -o X.csv writes.");
}

}  // namespace ctid::python
