// Python bindings of the oma layer (oma/oma.h, reached through its front door
// identification/output_only.h): ctid.oma(outputs, sample_time, options, channel_names,
// **options) runs identify_output_only, as `ctid oma` does, and returns an OmaResult with its
// modes, stabilisation diagram and verdict; OmaOptions, OmaMode, OmaPole, OmaMethod,
// OmaUncertainty and PoleStability mirror the C++ names. ctid.oma_setups(outputs, sample_time,
// channel_names, options, **options) merges several setups by PoSER or PreGER (MultiSetupOptions,
// MultiSetupResult).
#include "common.h"
#include "ctid/identification/output_only.h"
#include "fields.h"

namespace ctid::python {

void bind_oma(py::module_& m) {
  bind_enum<OmaMethod>(m, "OmaMethod", "Output-only identification method.");
  bind_enum<OmaUncertainty>(m, "OmaUncertainty",
                            "How the standard errors of the SSI modes are computed.");
  bind_enum<PoleStability>(m, "PoleStability", "Stability class of a pole in the diagram.");
  bind_options<OmaOptions>(m, "Options of output-only modal analysis (docs/oma.md).");
  bind_result<OmaPole>(m, "One pole of the stabilisation diagram.");
  bind_result<OmaMode>(m, "One identified mode with its standard errors.");
  bind_result<OmaResult>(m, "Output-only modal analysis: modes, diagram and verdict.")
      .def("converged", &OmaResult::converged, "Whether every order was identified.")
      .def("brief_report", &OmaResult::brief_report, "One line: why it ended.");
  m.def(
      "oma",
      [](const Eigen::MatrixXd& outputs, double sample_time,
         const std::optional<OmaOptions>& options,
         const std::optional<std::vector<std::string>>& channel_names, const py::kwargs& kwargs) {
        return identify_output_only(outputs, sample_time,
                                    options_from<OmaOptions>("oma", options, kwargs),
                                    channel_names.value_or(std::vector<std::string>{}));
      },
      py::arg("outputs"), py::arg("sample_time"), py::arg("options") = py::none(),
      py::arg("channel_names") = py::none(),
      "Output-only modal analysis of the (N, l) array `outputs` sampled every sample_time "
      "seconds: SSI-cov (or SSI-data, by method) over orders 2..max_order, or pLSCF (plscf) "
      "over polynomial orders, stable poles clustered into modes, standard errors by "
      "first-order perturbation or from segments; or fdd/efdd peaks. OmaOptions fields may be "
      "given as keywords, e.g. ctid.oma(y, h, method=ctid.OmaMethod.plscf, "
      "reference_channels=[0, 3]).");
  bind_enum<OmaMerge>(m, "OmaMerge", "How the modes of several setups are merged.");
  bind_options<MultiSetupOptions>(m, "Options of multi-setup output-only analysis (docs/oma.md).");
  bind_result<MultiSetupResult>(m, "The merged modes of several setups, and each setup's own.");
  m.def(
      "oma_setups",
      [](const std::vector<Eigen::MatrixXd>& outputs, double sample_time,
         const std::vector<std::vector<std::string>>& channel_names,
         const std::optional<MultiSetupOptions>& options, const py::kwargs& kwargs) {
        if (outputs.size() != channel_names.size()) {
          throw InvalidArgument(ctid::internal::concat("oma_setups: ", outputs.size(),
                                                       " records but ", channel_names.size(),
                                                       " lists of channel names"));
        }
        std::vector<OmaSetup> setups;
        for (std::size_t k = 0; k < outputs.size(); ++k) {
          setups.push_back({outputs[k], sample_time, channel_names[k]});
        }
        return identify_output_only(setups,
                                    options_from<MultiSetupOptions>("oma_setups", options, kwargs));
      },
      py::arg("outputs"), py::arg("sample_time"), py::arg("channel_names"),
      py::arg("options") = py::none(),
      "Several setups of one structure (a list of (N_k, l_k) arrays sampled every sample_time "
      "seconds, channel_names one list per setup) with the reference channels every setup "
      "measures (reference_names): each analysed alone and the modes merged into global ones "
      "by PoSER with standard errors carried through (merge=OmaMerge.poser, the default), or "
      "the setups identified together by PreGER with segment standard errors "
      "(merge=OmaMerge.preger). MultiSetupOptions fields may be given as keywords.");
}

}  // namespace ctid::python
