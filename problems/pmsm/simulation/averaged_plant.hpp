#pragma once
// The averaged plant: the dq machine with its flux model and the effect library's plant hooks
// (sensor offsets, inverter command shortfall and delay line, temperature profiles), integrated
// with a fixed-step RK4 much finer than the control period (docs/pmsm.md).
#include <memory>

#include "problems/pmsm/simulation/controlled_plant.hpp"
#include "problems/pmsm/simulation/drive_configuration.hpp"

namespace mhb::pmsm {

// The averaged plant of `spec` (its effects, no device settings), at rest at time 0.
std::unique_ptr<ControlledPlant> make_averaged_plant(const DriveSimulation& spec);

}  // namespace mhb::pmsm
