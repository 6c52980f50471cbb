// The extension module ctid._ctid: registers the exceptions, then one bind_<layer>() per layer.
// ctid::InvalidArgument becomes ctid.InvalidArgument (a ValueError) and
// ctid::ComputationError ctid.ComputationError (a RuntimeError), with the C++ message.
#include "common.h"
#include "ctid/core/error.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"

PYBIND11_MODULE(_ctid, m) {
  namespace py = pybind11;
  m.doc() =
      "ctid: continuous-time system identification from sampled data (C++ core). Use the "
      "`ctid` package, which re-exports everything here.";
  static PyObject* invalid_argument =
      py::register_exception<ctid::InvalidArgument>(m, "InvalidArgument", PyExc_ValueError).ptr();
  m.attr("InvalidArgument").attr("__doc__") =
      "Bad input to a ctid function (a ValueError); the message names the argument, "
      "its value and the rule.";
  static PyObject* computation_error =
      py::register_exception<ctid::ComputationError>(m, "ComputationError", PyExc_RuntimeError)
          .ptr();
  m.attr("ComputationError").attr("__doc__") =
      "A computation that could not be carried out on valid input (a RuntimeError).";
  // Registered last, so tried first: a message that echoes a file name whose bytes are not
  // UTF-8 becomes a Python str with those bytes written \xHH (decision 0042); given as they
  // are, Python could not decode the message and raised the exception without one.
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const ctid::InvalidArgument& e) {
      PyErr_SetString(invalid_argument, ctid::io::escape_invalid_utf8(e.what()).c_str());
    } catch (const ctid::ComputationError& e) {
      PyErr_SetString(computation_error, ctid::io::escape_invalid_utf8(e.what()).c_str());
    } catch (const ctid::io::IoError& e) {
      PyErr_SetString(PyExc_RuntimeError, ctid::io::escape_invalid_utf8(e.what()).c_str());
    }
  });
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
  ctid::python::bind_command_line(m);
}
