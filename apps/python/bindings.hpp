#pragma once
// The Python module hattr._hattr (docs/python.md): pybind11 over the library. The binding
// layer converts and delegates; what a function computes is the library's.

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/preprocess.hpp"

namespace hattr::python {

namespace py = pybind11;

/// Each part of the module adds its names.
void bindProfiles(py::module_& m);
void bindAnalysis(py::module_& m);
void bindStudies(py::module_& m);
void bindSimulation(py::module_& m);

/// The library's JSON as Python objects (dicts, lists, numbers, strings), through Python's json.
py::object toPython(const nlohmann::json& json);
/// A Python object (a dict of JSON values) as the library's JSON, through Python's json.
nlohmann::json fromPython(const py::handle& object);

/// Option strings as the CLI spells them: "paper", "zscore", "none"; "abs", "sq". Anything
/// else throws InputError naming the argument and the accepted values.
analysis::Normalization parseNormalization(std::string_view text);
analysis::DtwCost parseCost(std::string_view text);
/// The band as a fraction of the longer series; None (no band) arrives as a negative value.
analysis::DtwOptions dtwOptions(std::string_view cost, double band_fraction, double abandon_above);

}  // namespace hattr::python
