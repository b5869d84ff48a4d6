// hattr._hattr: the module's entry point, its exceptions and the helpers every part shares.

#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "hattr/core/error.hpp"
#include "hattr/version.hpp"

namespace hattr::python {

py::object toPython(const nlohmann::json& json) {
  // NaN (the report's "not available") travels as JSON null and arrives as None.
  return py::module_::import("json").attr("loads")(json.dump());
}

nlohmann::json fromPython(const py::handle& object) {
  const std::string text = py::str(py::module_::import("json").attr("dumps")(object));
  return nlohmann::json::parse(text);
}

FloatArray floatArray(const py::handle& values, std::string_view name) {
  const py::array array = py::array::ensure(values);
  const char kind = array ? array.dtype().kind() : 'O';
  HATTR_THROW_UNLESS(kind == 'f' || kind == 'i' || kind == 'u',
                     "{}: expected numbers (an array or a sequence of real numbers), got {}", name,
                     array ? std::string(py::str(array.dtype())) : std::string(py::str(py::type::of(values))));
  return FloatArray::ensure(array);
}

analysis::DtwOptions dtwOptions(std::string_view cost, std::optional<double> band_fraction, double abandon_above) {
  return {.cost = analysis::parseDtwCost(cost), .band_fraction = band_fraction.value_or(-1.0),
          .abandon_above = abandon_above};
}

namespace {

/// hattr.Error (a RuntimeError) for every hattr error, and hattr.InputError, also a ValueError,
/// for bad input; each carries the library's message unchanged.
void registerExceptions(py::module_& m) {
  // Kept for the life of the process, never destroyed (their destructors would run after the
  // interpreter is gone).
  static auto& error = *new py::exception<Error>(m, "Error", PyExc_RuntimeError);
  error.doc() = "Base of every error hattr raises: the library's message, unchanged.";
  error.attr("__module__") = "hattr";
  const py::tuple input_bases = py::make_tuple(error, py::handle(PyExc_ValueError));
  static auto& input_error = *new py::exception<InputError>(m, "InputError", input_bases);
  input_error.doc() =
      "Bad input (a file, an argument, a study): what, where, what was expected and what was found. "
      "A ValueError and a hattr.Error.";
  input_error.attr("__module__") = "hattr";
  // Translators run newest first: InputError before the Error it derives from.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });
}

}  // namespace
}  // namespace hattr::python

PYBIND11_MODULE(_hattr, m) {
  namespace hp = hattr::python;
  m.doc() = "hattr: motor skill training with haptic attributes (the C++ library's Python module). "
            "SI units throughout: metres, seconds, newtons.";
  m.attr("__version__") = hattr::kVersion;
  hp::registerExceptions(m);
  hp::bindProfiles(m);
  hp::bindAnalysis(m);
  hp::bindStudies(m);
  hp::bindSimulation(m);
  hp::bindDevices(m);
  hp::bindLibrary(m);
}
