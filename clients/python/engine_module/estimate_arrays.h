// Session estimates as numpy structured arrays: one row per frame (position sessions: the
// tracker's state, its standard deviations, presence, health, per-pair delays), and one row
// per frame and source for sessions that list sources (directions). Field names follow
// engine/core/estimate.h and the CLI's estimates.csv (clients/io/csv_io.h), SI units.
#pragma once

#include <pybind11/numpy.h>

#include <vector>

#include "engine/core/estimate.h"

namespace localizer::python {

namespace py = pybind11;

// The frame row's dtype; pair_count > 0 adds delay_s and quality of shape (pair_count,).
py::dtype EstimateDtype(int pair_count);
py::array EstimatesToArray(const std::vector<engine::Estimate>& estimates, int pair_count);

py::dtype SourceDtype();
// Every frame's Estimate::sources, in frame order then source id.
py::array SourcesToArray(const std::vector<engine::Estimate>& estimates);

}  // namespace localizer::python
