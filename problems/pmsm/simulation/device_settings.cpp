#include "problems/pmsm/simulation/device_settings.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "problems/pmsm/simulation/drive_configuration.hpp"

namespace mhb::pmsm {

void check_device_settings(const DeviceSettings& device, const DriveControl& control) {
    const auto& inv = device.inverter;
    if (!(inv.pwm_frequency > 0)) throw std::invalid_argument("inverter.pwm_frequency must be positive");
    const double carriers = control.control_period * inv.pwm_frequency;
    if (std::llround(carriers) < 1 || std::abs(carriers - static_cast<double>(std::llround(carriers))) > 1e-6 * carriers)
        throw std::invalid_argument(fmt::format(
            "inverter.pwm_frequency x control_period = {} must be a whole number >= 1 (the currents are sampled at a "
            "carrier peak once per control period)", carriers));
    if (!(inv.dead_time >= 0) || inv.dead_time >= 0.25 / inv.pwm_frequency)
        throw std::invalid_argument("inverter.dead_time must lie in [0, a quarter of the carrier period)");
    if (!(inv.switch_drop >= 0) || !(inv.diode_drop >= 0) || !(inv.switch_resistance >= 0) || !(inv.diode_resistance >= 0))
        throw std::invalid_argument("inverter device drops and on-resistances must not be negative");
    if (device.encoder.lines < 0) throw std::invalid_argument("encoder.lines must not be negative");
    for (const auto& h : device.rotor_flux.harmonics)
        if (h.order < 5 || h.order % 2 == 0 || h.order % 3 == 0 || !(h.amplitude >= 0))
            throw std::invalid_argument(fmt::format(
                "rotor_flux harmonic order {} amplitude {}: orders are odd, not multiples of 3, >= 5; amplitudes >= 0",
                h.order, h.amplitude));
    if (!(device.rotor_flux.eccentricity >= 0 && device.rotor_flux.eccentricity <= 0.5))
        throw std::invalid_argument(fmt::format("rotor_flux.eccentricity {} must lie in [0, 0.5] (a relative modulation of the magnet flux)",
                                                device.rotor_flux.eccentricity));
    if (!(std::abs(device.rotor_flux.eccentricity_phase) <= std::numbers::pi))
        throw std::invalid_argument("rotor_flux.eccentricity_phase must lie in [-pi, pi]");
    if (!(device.saturation.saturation_current >= 0))
        throw std::invalid_argument("saturation.saturation_current must not be negative");
    const auto& th = device.thermal;
    if (!(th.winding_capacity > 0 && th.magnet_capacity > 0 && th.winding_to_magnet > 0 && th.winding_to_ambient > 0 &&
          th.magnet_to_ambient > 0 && th.iron_loss >= 0))
        throw std::invalid_argument("thermal capacities and resistances must be positive, iron_loss not negative");
}

}  // namespace mhb::pmsm
