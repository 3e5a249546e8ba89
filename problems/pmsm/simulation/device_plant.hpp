#pragma once
// The device plant: a drive written from the physics of its devices rather than from the averaged
// model terms the fit uses (problems/pmsm/effects/ is deliberately not used here). A switching-level
// two-level inverter with centre-aligned PWM, dead time and device drops feeds the machine in the
// stationary frame, integrated exactly across each interval between switching instants; the currents
// are sampled at the carrier peak and the reference computed from them is applied one control period
// later; an incremental encoder, two current sensors, a rotor whose magnet flux carries spatial
// harmonics, saturating iron and a two-node thermal network complete it. docs/pmsm.md, "The device
// plant", gives every equation.
#include <memory>

#include "problems/pmsm/simulation/controlled_plant.hpp"
#include "problems/pmsm/simulation/device_settings.hpp"

namespace mhb::pmsm {

struct DriveSimulation;

// The device plant of `spec` (spec.device must be set), at rest at time 0.
std::unique_ptr<ControlledPlant> make_device_plant(const DriveSimulation& spec);

}  // namespace mhb::pmsm
