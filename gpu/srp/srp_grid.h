// Direction grids for the batched SRP-PHAT (srp_batch.h): unit vectors from the array towards
// the source, in the sensors' frame.
#pragma once

#include <vector>

#include "engine/core/types.h"
#include "gpu/srp/srp_array.h"

namespace localizer::gpu {

// `count` points of a Fibonacci lattice over the whole sphere (point i at height
// 1 - (2 i + 1) / count, longitude i pi (3 - sqrt 5)): near-uniform, any count.
std::vector<engine::Vec3> FibonacciDirections(int count);

// The grid engine::SrpPhat searches for this array: its roots, the same lattice and count
// (engine/doa/srp_phat.cc: as many as leaves of half a sample of lag cover the sphere, times
// 1.5^2, within [128, 8192]); planar arrays keep the points whose cells reach the normal's
// hemisphere; linear arrays get the CPU's arcs of cone angle as unit vectors in the plane of the
// axis and a perpendicular (only the cone angle is observable). At 16 kHz: 291 directions on
// the ReSpeaker board's hemisphere (4 microphones 8.1 cm apart), 1567 on the sphere for a
// tetrahedron of 14 cm edges, 42 cone angles for 8 microphones over 28 cm.
std::vector<engine::Vec3> CpuLikeGrid(const SrpArrayModel& array);

}  // namespace localizer::gpu
