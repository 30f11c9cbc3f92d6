#pragma once
#include <pybind11/pybind11.h>

// Adds mcrecon.report() to the module.
void add_report_binding(pybind11::module_& m);
