// One Register function per part of localizer.engine, each in the file named for it.
#pragma once

#include <pybind11/pybind11.h>

namespace localizer::python {

void RegisterSession(pybind11::module_& m);    // session_bindings.cc
void RegisterTdoa(pybind11::module_& m);       // tdoa_bindings.cc: GCC-PHAT, multilateration
void RegisterSimulator(pybind11::module_& m);  // sim_bindings.cc
void RegisterAttitude(pybind11::module_& m);   // attitude_bindings.cc
void RegisterTws(pybind11::module_& m);        // tws_bindings.cc

}  // namespace localizer::python
