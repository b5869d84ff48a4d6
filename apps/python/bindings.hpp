#pragma once
// The Python module hattr._hattr (docs/python.md): pybind11 over the library. The binding
// layer converts and delegates; what a function computes is the library's.

#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "hattr/analysis/dtw.hpp"

namespace hattr::python {

namespace py = pybind11;

/// Each part of the module adds its names.
void bindProfiles(py::module_& m);
void bindAnalysis(py::module_& m);
void bindStudies(py::module_& m);
void bindSimulation(py::module_& m);
void bindDevices(py::module_& m);
void bindLibrary(py::module_& m);

/// The library's JSON as Python objects (dicts, lists, numbers, strings), through Python's json.
py::object toPython(const nlohmann::json& json);
/// A Python object (a dict of JSON values) as the library's JSON, through Python's json.
nlohmann::json fromPython(const py::handle& object);

/// Float64 arrays, C-contiguous (a NumPy view of another layout or type is copied into one).
using FloatArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// A numeric argument (a NumPy array, a list of numbers, a pandas column) as a float64 array.
/// Anything else (text, complex numbers, objects) throws InputError naming `name`; a copy is
/// made only when the layout or type needs one.
FloatArray floatArray(const py::handle& values, std::string_view name);

/// The DTW options from Python's arguments: cost "abs" or "sq", the band as a fraction of the
/// longer series (None: no band), the abandon bound.
analysis::DtwOptions dtwOptions(std::string_view cost, std::optional<double> band_fraction, double abandon_above);

}  // namespace hattr::python
