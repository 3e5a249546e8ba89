#include "problems/pmsm/simulation/drive_configuration.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "problems/pmsm/machine/flux_models.hpp"

namespace mhb::pmsm {

double TemperatureProfile::at(double t) const {
    if (points.empty()) return reference_temperature;
    if (t <= points.front().first) return points.front().second;
    if (t >= points.back().first) return points.back().second;
    const auto it = std::upper_bound(points.begin(), points.end(), t,
                                     [](double x, const std::pair<double, double>& p) { return x < p.first; });
    const auto& [t1, y1] = *it;
    const auto& [t0, y0] = *(it - 1);
    return y0 + (y1 - y0) * (t - t0) / (t1 - t0);
}

std::int64_t whole_ratio(double a, double b, const char* what) {
    const double r = a / b;
    const auto n = static_cast<std::int64_t>(std::llround(r));
    if (n < 1 || std::abs(r - static_cast<double>(n)) > 1e-6 * r)
        throw std::invalid_argument(fmt::format("{} ({} / {} = {}) must be a whole number >= 1", what, a, b, r));
    return n;
}

DriveSimulation with_device(const DriveSimulation& base, const DeviceSettings& device, std::uint64_t seed) {
    DriveSimulation d;
    d.motor = base.motor;
    d.mechanics = base.mechanics;
    d.control = base.control;
    d.logging = base.logging;
    d.noise = base.noise;
    d.seed = seed;
    d.segments = base.segments;
    d.base_directory = base.base_directory;
    d.device = device;
    return d;
}

std::unique_ptr<FluxModel> plant_flux_model(const DriveSimulation& spec) {
    if (spec.device) {
        if (spec.device->saturation.saturation_current > 0)
            return std::make_unique<SaturatingIron>(spec.motor.ld, spec.motor.lq, spec.device->saturation.saturation_current);
        return std::make_unique<LinearFlux>(spec.motor.ld, spec.motor.lq);
    }
    std::unique_ptr<FluxModel> flux = std::make_unique<LinearFlux>(spec.motor.ld, spec.motor.lq);
    for (const auto& e : spec.effects)
        if (auto replacement = e->plant_flux_model(spec.motor, {spec.control.current_limit, spec.motor.psi_f}, spec.base_directory))
            flux = std::move(replacement);
    return flux;
}

}  // namespace mhb::pmsm
