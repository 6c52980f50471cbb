// The extension module ctid._ctid: registers the exceptions, then one bind_<layer>() per layer.
// ctid::InvalidArgument becomes ctid.InvalidArgument (a ValueError) and
// ctid::ComputationError ctid.ComputationError (a RuntimeError), with the C++ message.
#include "common.h"
#include "ctid/core/error.h"

PYBIND11_MODULE(_ctid, m) {
  namespace py = pybind11;
  m.doc() =
      "ctid: continuous-time system identification from sampled data (C++ core). Use the "
      "`ctid` package, which re-exports everything here.";
  py::register_exception<ctid::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError)
      .attr("__doc__") =
      "Bad input to a ctid function (a ValueError); the message names the argument, "
      "its value and the rule.";
  py::register_exception<ctid::ComputationError>(m, "ComputationError", PyExc_RuntimeError)
      .attr("__doc__") =
      "A computation that could not be carried out on valid input (a RuntimeError).";
  ctid::python::bind_core(m);
  ctid::python::bind_simulation(m);
  ctid::python::bind_frequency(m);
  ctid::python::bind_estimation(m);
  ctid::python::bind_refined_iv(m);
  ctid::python::bind_frf_fit(m);
  ctid::python::bind_identification(m);
  ctid::python::bind_process_model(m);
  ctid::python::bind_delayed_feedback(m);
  ctid::python::bind_oma(m);
  ctid::python::bind_study(m);
  ctid::python::bind_io(m);
  ctid::python::bind_response(m);
}
