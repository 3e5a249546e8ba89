#pragma once
// Closed-loop field-oriented PMSM drive as in the seed (its Fig. 5): current PI loops with decoupling,
// a speed PI loop and an optional position loop, the harmonic reducer's load reflected to the motor,
// a fixed-step RK4 plant much finer than the control period, and a log of what a real drive logs:
// the controller's voltage references and its measured currents, speed and angle. Physical effects
// (effects/) act on the plant and the sensors only; the controller knows the nominal motor. With
// `device` set, the plant is instead the device plant (device_plant.hpp), written from the physics of
// each device, and no effect may be given. docs/pmsm.md describes loops, tuning, integrator and logging.
#include "problems/pmsm/simulation/drive_configuration.hpp"

namespace mhb::pmsm {

// Runs the whole profile on the plant it selects. Throws std::invalid_argument on inconsistent
// settings (e.g. an integration step that does not divide the control period, effects with a device
// plant).
SimulationResult simulate(const DriveSimulation& spec);

// The sensors' noise as the residual of the true base model sees it: that residual on `noisy` less
// that on `clean` (the same drive simulated without noise), row by row over `rows` (pairs of first
// row and row count; the whole log when empty), its standard deviation on u_d and u_q. What a noise
// estimate from the data should find: the current sensors' noise enters the residual through R i
// and omega L i as the voltage's own does. NaN when the two logs differ in length.
Eigen::Vector2d sensor_noise_in_residual(const MotorParameters& motor, const Measurement& noisy, const Measurement& clean,
                                         const std::vector<std::pair<Eigen::Index, Eigen::Index>>& rows = {});

}  // namespace mhb::pmsm
