#include "problems/pmsm/simulation/drive_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "framework/random.hpp"
#include "problems/pmsm/simulation/averaged_plant.hpp"
#include "problems/pmsm/simulation/controlled_plant.hpp"
#include "problems/pmsm/simulation/device_plant.hpp"
#include "problems/pmsm/simulation/field_oriented_controller.hpp"

namespace mhb::pmsm {
namespace {

// First-order low-pass at the control rate (identity when the cutoff is 0).
class LowPass {
public:
    LowPass(double cutoff_hz, double period) : gain_(cutoff_hz > 0 ? 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff_hz * period) : 1.0) {}
    double update(double x) {
        y_ = started_ ? y_ + gain_ * (x - y_) : x;
        started_ = true;
        return y_;
    }

private:
    double gain_;
    double y_ = 0.0;
    bool started_ = false;
};

}  // namespace

Eigen::Vector2d sensor_noise_in_residual(const MotorParameters& motor, const Measurement& noisy, const Measurement& clean,
                                         const std::vector<std::pair<Eigen::Index, Eigen::Index>>& rows) {
    if (noisy.size() != clean.size()) return Eigen::Vector2d::Constant(std::nan(""));
    const auto residual = [&](const Measurement& m, Eigen::Index k, int axis) {
        const double w = m.omega_e[k];
        return axis == 0 ? m.u_d[k] - (motor.rs * m.i_d[k] - w * motor.lq * m.i_q[k])
                         : m.u_q[k] - (motor.rs * m.i_q[k] + w * (motor.ld * m.i_d[k] + motor.psi_f));
    };
    const std::vector<std::pair<Eigen::Index, Eigen::Index>> all{{0, noisy.size()}};
    Eigen::Vector2d out;
    for (int a = 0; a < 2; ++a) {
        double sum = 0.0, square = 0.0, n = 0.0;
        for (const auto& [first, count] : rows.empty() ? all : rows)
            for (Eigen::Index k = first; k < first + count; ++k) {
                const double d = residual(noisy, k, a) - residual(clean, k, a);
                sum += d;
                square += d * d;
                n += 1.0;
            }
        out[a] = n > 0.0 ? std::sqrt(std::max(0.0, square / n - (sum / n) * (sum / n))) : std::nan("");
    }
    return out;
}

SimulationResult simulate(const DriveSimulation& spec) {
    const auto& c = spec.control;
    const auto& motor = spec.motor;
    if (spec.segments.empty()) throw std::invalid_argument("a simulation needs at least one segment");
    if (!(motor.rs > 0 && motor.ld > 0 && motor.lq > 0 && motor.psi_f > 0 && motor.pole_pairs > 0))
        throw std::invalid_argument("motor parameters must be positive");
    if (spec.device && !spec.effects.empty())
        throw std::invalid_argument("the device plant takes its imperfections from its device settings; library "
                                    "effects act on the averaged plant only");
    whole_ratio(c.control_period, c.integration_step, "control_period / integration_step");
    const std::int64_t controls_per_log = whole_ratio(spec.logging.period, c.control_period, "logging period / control_period");
    const double ts = c.control_period;

    std::unique_ptr<ControlledPlant> plant;
    if (spec.device) plant = make_device_plant(spec);
    else plant = make_averaged_plant(spec);
    FieldOrientedController controller(motor, spec.mechanics, c);
    const Complex log_offset = plant->logged_voltage_offset();

    Rng rng(spec.seed);
    Rng transient_rng(derive_seed(spec.seed, "logging", "transients", 0));
    LowPass f_id(spec.logging.filter_cutoff, ts), f_iq(spec.logging.filter_cutoff, ts), f_ud(spec.logging.filter_cutoff, ts),
        f_uq(spec.logging.filter_cutoff, ts), f_w(spec.logging.filter_cutoff, ts);

    const auto settle_controls_of = [&](const Segment& s) { return static_cast<std::int64_t>(std::llround(s.settle / ts)); };
    // The settling is logged on the window's own grid, backwards from its first sample, so each
    // segment's samples are evenly spaced.
    const auto settle_rows_of = [&](const Segment& s) {
        return spec.logging.transients ? settle_controls_of(s) / controls_per_log : std::int64_t{0};
    };
    std::int64_t total_samples = 0;
    for (const auto& s : spec.segments) total_samples += s.samples + settle_rows_of(s);
    SimulationResult result;
    Measurement& m = result.data;
    m.i_d.resize(total_samples);
    m.i_q.resize(total_samples);
    m.u_d.resize(total_samples);
    m.u_q.resize(total_samples);
    m.omega_e.resize(total_samples);
    if (spec.logging.time) m.t.emplace(total_samples);
    if (spec.logging.theta) m.theta_e.emplace(total_samples);
    if (spec.logging.shaft_angle) m.theta_m.emplace(total_samples);
    if (spec.logging.temperatures) {
        m.temp_winding.emplace(total_samples);
        m.temp_magnet.emplace(total_samples);
    }
    m.segment.resize(total_samples);

    std::int64_t control_index = 0;
    Eigen::Index row = 0;

    for (std::size_t seg = 0; seg < spec.segments.size(); ++seg) {
        const Segment& segment = spec.segments[seg];
        const auto settle_controls = settle_controls_of(segment);
        const std::int64_t first_logged = settle_controls - settle_rows_of(segment) * controls_per_log;
        const std::int64_t controls = settle_controls + segment.samples * controls_per_log;
        // Segments sharing a label share its index (labels are distinct, in order of first use).
        const auto label_it = std::find(m.segment_labels.begin(), m.segment_labels.end(), segment.label);
        const int label_index = static_cast<int>(label_it - m.segment_labels.begin());
        if (label_it == m.segment_labels.end()) m.segment_labels.push_back(segment.label);
        result.segments.push_back({segment.label, row + settle_rows_of(segment), segment.samples,
                                   static_cast<double>(control_index) * ts, row});

        for (std::int64_t j = 0; j < controls; ++j, ++control_index) {
            const double t = static_cast<double>(control_index) * ts;
            const SensorReading reading = plant->sense(t, rng);
            const Complex i_c = park(reading.current, reading.angle);
            double omega_c = controller.estimate_speed(reading.angle, reading.true_speed);
            if (spec.noise.speed > 0) omega_c += spec.noise.speed * rng.normal();
            const Complex u_ref = controller.update(segment, i_c, omega_c);

            // Logging: filtered at the control rate, sampled every logging period inside the window.
            const double id_f = f_id.update(i_c.real()), iq_f = f_iq.update(i_c.imag());
            const double ud_f = f_ud.update(u_ref.real()), uq_f = f_uq.update(u_ref.imag());
            const double w_f = f_w.update(omega_c);
            if (j >= first_logged && (j - first_logged) % controls_per_log == 0) {
                Rng& log_rng = j < settle_controls ? transient_rng : rng;
                m.i_d[row] = id_f;
                m.i_q[row] = iq_f;
                m.u_d[row] = ud_f + (spec.noise.voltage > 0 ? spec.noise.voltage * log_rng.normal() : 0.0);
                m.u_q[row] = uq_f + (spec.noise.voltage > 0 ? spec.noise.voltage * log_rng.normal() : 0.0);
                if (log_offset != Complex{}) {
                    m.u_d[row] += log_offset.real();
                    m.u_q[row] += log_offset.imag();
                }
                m.omega_e[row] = w_f;
                if (m.t) (*m.t)[row] = t;
                if (m.theta_e) (*m.theta_e)[row] = reading.angle;
                if (m.theta_m) (*m.theta_m)[row] = reading.shaft_angle;
                if (m.temp_winding) {
                    const Temperatures temperatures = plant->temperatures(t);
                    (*m.temp_winding)[row] = temperatures.winding + (spec.noise.temperature > 0 ? spec.noise.temperature * log_rng.normal() : 0.0);
                    (*m.temp_magnet)[row] = temperatures.magnet + (spec.noise.temperature > 0 ? spec.noise.temperature * log_rng.normal() : 0.0);
                }
                m.segment[row] = label_index;
                ++row;
            }
            plant->run_control_period(t, u_ref, reading, omega_c, segment);
        }
    }
    if (!spec.logging.segment) {
        m.segment_labels.clear();
        m.segment.resize(0);
    }
    result.simulated_time = static_cast<double>(control_index) * ts;
    result.integration_steps = plant->integration_steps();
    return result;
}

}  // namespace mhb::pmsm
