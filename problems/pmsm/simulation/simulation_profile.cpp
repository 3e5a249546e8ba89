#include "problems/pmsm/simulation/simulation_profile.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

long line_of(const toml::node& n) { return static_cast<long>(n.source().begin.line); }

// Typed access to one TOML table, refusing unknown keys, wrong types and out-of-range values with
// the file, line and dotted field name.
class TableReader {
public:
    TableReader(const std::string& file, const toml::table& table, std::string prefix, long line)
        : file_(file), table_(table), prefix_(std::move(prefix)), line_(line) {}

    // Refuses keys outside `allowed` (typos must not pass silently).
    void allow_only(std::initializer_list<std::string_view> allowed) const {
        for (auto&& [key, node] : table_) {
            bool known = false;
            for (auto a : allowed) known = known || key.str() == a;
            if (!known) {
                std::string list;
                for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
                throw InputError(file_, line_of(node), field(key.str()), "unknown key (allowed: " + list + ")");
            }
        }
    }

    // A number in [lo, hi] (lo excluded when `positive`), or `fallback` when absent.
    double number(std::string_view key, double fallback, double lo, double hi, bool positive = false) const {
        const toml::node* n = table_.get(key);
        if (!n) return fallback;
        if (!n->is_number()) throw InputError(file_, line_of(*n), field(key), "expects a number");
        const std::optional<double> v = n->value<double>();  // empty for an integer beyond ±2^53
        if (!v || !std::isfinite(*v) || *v < lo || *v > hi || (positive && *v <= 0.0)) {
            const std::string range = positive && lo <= 0 ? fmt::format("(0, {}]", hi) : fmt::format("[{}, {}]", lo, hi);
            const std::string got = n->is_integer() ? std::to_string(n->as_integer()->get()) : fmt::format("{}", *v);
            throw InputError(file_, line_of(*n), field(key), fmt::format("must lie in {} (got {})", range, got));
        }
        return *v;
    }

    std::int64_t integer(std::string_view key, std::int64_t fallback, std::int64_t lo, std::int64_t hi) const {
        const toml::node* n = table_.get(key);
        if (!n) return fallback;
        if (!n->is_integer()) throw InputError(file_, line_of(*n), field(key), "expects an integer");
        const auto v = n->value<std::int64_t>().value();
        if (v < lo || v > hi) throw InputError(file_, line_of(*n), field(key), fmt::format("must lie in [{}, {}] (got {})", lo, hi, v));
        return v;
    }

    bool boolean(std::string_view key, bool fallback) const {
        const toml::node* n = table_.get(key);
        if (!n) return fallback;
        if (!n->is_boolean()) throw InputError(file_, line_of(*n), field(key), "expects true or false");
        return n->value<bool>().value();
    }

    const toml::node* get(std::string_view key) const { return table_.get(key); }
    const toml::table& table() const { return table_; }
    std::string field(std::string_view key) const { return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key); }
    long line() const { return line_; }
    const std::string& file() const { return file_; }

private:
    const std::string& file_;
    const toml::table& table_;
    std::string prefix_;
    long line_;
};

// The table at `key` of the root, or an empty one; anything else under that name is an error.
const toml::table& subtable(const std::string& file, const toml::table& root, std::string_view key) {
    static const toml::table empty;
    const toml::node* n = root.get(key);
    if (!n) return empty;
    if (!n->is_table()) throw InputError(file, line_of(*n), std::string(key), "expects a table");
    return *n->as_table();
}

TemperatureProfile read_temperature(const TableReader& r, std::string_view key) {
    TemperatureProfile profile;
    const toml::node* n = r.get(key);
    if (!n) return profile;
    const std::string field = r.field(key);
    if (n->is_number()) {
        profile.points = {{0.0, r.number(key, 0, -273.15, 1000.0)}};
        return profile;
    }
    const toml::array* points = n->as_array();
    if (!points || points->empty())
        throw InputError(r.file(), line_of(*n), field, "expects a temperature in °C or a list of [t, T] pairs");
    profile.points.clear();
    for (const auto& point : *points) {
        const toml::array* pair = point.as_array();
        if (!pair || pair->size() != 2 || !(*pair)[0].is_number() || !(*pair)[1].is_number())
            throw InputError(r.file(), line_of(point), field, "each point is [t in s, temperature in °C]");
        const std::optional<double> t_read = (*pair)[0].value<double>(), temp_read = (*pair)[1].value<double>();
        const double t = t_read.value_or(inf), temp = temp_read.value_or(inf);  // empty beyond ±2^53
        if (!std::isfinite(t) || !std::isfinite(temp) || temp < -273.15 || temp > 1000.0)
            throw InputError(r.file(), line_of(point), field, "time and temperature must be finite, temperature >= -273.15 °C");
        if (!profile.points.empty() && t <= profile.points.back().first)
            throw InputError(r.file(), line_of(point), field, "times must increase");
        profile.points.emplace_back(t, temp);
    }
    return profile;
}

std::unique_ptr<Effect> read_effect(const std::string& file, const std::string& name, const toml::node& node,
                                    bool& enabled) {
    const std::string field = "effects." + name;
    const toml::table* table = node.as_table();
    if (!table) throw InputError(file, line_of(node), field, "expects a table of the effect's parameters");
    const auto* entry = EffectRegistry::instance().find(name);
    if (!entry) {
        std::string known;
        for (const auto* e : EffectRegistry::instance().entries()) known += (known.empty() ? "" : ", ") + e->name;
        throw InputError(file, line_of(node), field, "unknown effect (registered: " + known + ")");
    }
    enabled = true;
    std::map<std::string, ParameterValue> values;
    std::map<std::string, long> lines;
    for (auto&& [key, value] : *table) {
        const std::string k(key.str());
        if (k == "enabled") {
            if (!value.is_boolean()) throw InputError(file, line_of(value), field + ".enabled", "expects true or false");
            enabled = value.value<bool>().value();
            continue;
        }
        lines[k] = line_of(value);
        if (value.is_integer()) values[k] = value.value<std::int64_t>().value();
        else if (value.is_floating_point()) values[k] = value.value<double>().value();
        else if (value.is_boolean()) values[k] = value.value<bool>().value();
        else if (value.is_string()) values[k] = value.value<std::string>().value();
        else throw InputError(file, line_of(value), field + "." + k, "expects a number, a boolean or a string");
        bool declared = false;
        for (const auto& spec : entry->parameters) declared = declared || spec.name == k;
        if (!declared) {
            std::string list = "enabled";
            for (const auto& spec : entry->parameters) list += ", " + spec.name;
            throw InputError(file, line_of(value), field + "." + k, "unknown parameter (allowed: " + list + ")");
        }
    }
    try {
        return make_effect(name, values);
    } catch (const ParameterError& e) {
        const auto it = lines.find(e.field());
        throw InputError(file, it == lines.end() ? line_of(node) : it->second, field + "." + e.field(), e.message());
    }
}

Segment read_segment(const std::string& file, const toml::node& node, std::size_t index, double log_period) {
    const std::string prefix = fmt::format("segment[{}]", index + 1);
    const toml::table* table = node.as_table();
    if (!table) throw InputError(file, line_of(node), prefix, "expects a table");
    TableReader r(file, *table, prefix, line_of(node));
    r.allow_only({"label", "speed", "load_torque", "i_d", "settle", "samples", "duration"});
    Segment s;
    s.label = std::to_string(index + 1);
    if (const toml::node* label = r.get("label")) {
        if (label->is_integer()) s.label = std::to_string(label->value<std::int64_t>().value());
        else if (label->is_string()) s.label = label->value<std::string>().value();
        else throw InputError(file, line_of(*label), r.field("label"), "expects a string or an integer");
        if (s.label.empty() || s.label.find_first_of(",\"\n\r") != std::string::npos ||
            s.label.front() == ' ' || s.label.back() == ' ')
            throw InputError(file, line_of(*label), r.field("label"),
                             "must be non-empty, without commas, quotes, line breaks or surrounding spaces");
    }
    s.speed_rpm = r.number("speed", 0.0, -1e5, 1e5);
    s.load_torque = r.number("load_torque", 0.0, -1e4, 1e4);
    s.i_d = r.number("i_d", 0.0, -1e4, 1e4);
    s.settle = r.number("settle", 0.0, 0.0, 1e4);
    const bool has_samples = r.get("samples") != nullptr, has_duration = r.get("duration") != nullptr;
    if (has_samples == has_duration)
        throw InputError(file, line_of(node), prefix, "give exactly one of samples (count) and duration (s)");
    if (has_samples) {
        s.samples = r.integer("samples", 0, 1, max_measurement_rows);
    } else {
        const double duration = r.number("duration", 0.0, 0.0, 1e5, true);
        const double periods = std::round(duration / log_period);
        if (periods < 1)
            throw InputError(file, line_of(*r.get("duration")), r.field("duration"), "shorter than one logging period");
        if (periods > static_cast<double>(max_measurement_rows))
            throw InputError(file, line_of(*r.get("duration")), r.field("duration"),
                             fmt::format("{} s at a logging period of {} s is {:.0f} samples; the limit is {} per profile",
                                         duration, log_period, periods, max_measurement_rows));
        s.samples = static_cast<std::int64_t>(periods);
    }
    return s;
}


// The [plant] table: model = "averaged" (the default: the effect library acts on the averaged dq
// plant) or "device" with the device tables below; docs/pmsm.md, "The device plant".
const toml::table& device_subtable(const std::string& file, const toml::table& plant, std::string_view key) {
    static const toml::table empty;
    const toml::node* n = plant.get(key);
    if (!n) return empty;
    if (!n->is_table()) throw InputError(file, line_of(*n), "plant." + std::string(key), "expects a table");
    return *n->as_table();
}

long line_of_key(const toml::table& t, std::string_view key, long fallback) {
    const toml::node* n = t.get(key);
    return n ? line_of(*n) : fallback;
}

InverterDevice read_inverter(const std::string& file, const toml::table& plant, double control_period) {
    const auto& t = device_subtable(file, plant, "inverter");
    TableReader r(file, t, "plant.inverter", 0);
    r.allow_only({"pwm_frequency", "dead_time", "switch_drop", "diode_drop", "switch_resistance", "diode_resistance",
                  "delay_compensation"});
    InverterDevice inv;
    inv.pwm_frequency = r.number("pwm_frequency", inv.pwm_frequency, 0.0, 1e7, true);
    inv.dead_time = r.number("dead_time", inv.dead_time, 0.0, 1e-3);
    inv.switch_drop = r.number("switch_drop", inv.switch_drop, 0.0, 100.0);
    inv.diode_drop = r.number("diode_drop", inv.diode_drop, 0.0, 100.0);
    inv.switch_resistance = r.number("switch_resistance", inv.switch_resistance, 0.0, 1e3);
    inv.diode_resistance = r.number("diode_resistance", inv.diode_resistance, 0.0, 1e3);
    inv.delay_compensation = r.boolean("delay_compensation", inv.delay_compensation);
    // The currents are sampled at a carrier peak once per control period, so whole carriers must
    // tile it; the dead time must leave every pulse its two edges.
    const double carriers = control_period * inv.pwm_frequency;
    if (std::llround(carriers) < 1 || std::abs(carriers - static_cast<double>(std::llround(carriers))) > 1e-6 * carriers)
        throw InputError(file, line_of_key(t, "pwm_frequency", line_of_key(plant, "inverter", 0)), "plant.inverter.pwm_frequency",
                         fmt::format("pwm_frequency x drive.control_period = {} must be a whole number >= 1", carriers));
    if (inv.dead_time >= 0.25 / inv.pwm_frequency)
        throw InputError(file, line_of_key(t, "dead_time", 0), "plant.inverter.dead_time",
                         fmt::format("must be shorter than a quarter of the carrier period ({} s)", 0.25 / inv.pwm_frequency));
    return inv;
}

RotorFluxDevice read_rotor_flux(const std::string& file, const toml::table& plant) {
    const auto& t = device_subtable(file, plant, "rotor_flux");
    TableReader r(file, t, "plant.rotor_flux", 0);
    r.allow_only({"harmonics", "eccentricity", "eccentricity_phase"});
    RotorFluxDevice rotor;
    rotor.eccentricity = r.number("eccentricity", 0.0, 0.0, 0.5);
    rotor.eccentricity_phase = r.number("eccentricity_phase", 0.0, -std::numbers::pi, std::numbers::pi);
    auto& harmonics = rotor.harmonics;
    const toml::node* n = t.get("harmonics");
    if (!n) return rotor;
    const toml::array* list = n->as_array();
    if (!list) throw InputError(file, line_of(*n), "plant.rotor_flux.harmonics", "expects a list of {order, amplitude, phase} tables");
    for (std::size_t k = 0; k < list->size(); ++k) {
        const toml::node& item = (*list)[k];
        const std::string field = fmt::format("plant.rotor_flux.harmonics[{}]", k + 1);
        if (!item.is_table()) throw InputError(file, line_of(item), field, "expects a table {order = 5, amplitude = 0.01, phase = 0.0}");
        TableReader h(file, *item.as_table(), field, line_of(item));
        h.allow_only({"order", "amplitude", "phase"});
        if (!item.as_table()->get("order")) throw InputError(file, line_of(item), field + ".order", "is required");
        FluxHarmonic harmonic;
        harmonic.order = static_cast<int>(h.integer("order", 5, 5, 99));
        if (harmonic.order % 2 == 0 || harmonic.order % 3 == 0)
            throw InputError(file, line_of(*item.as_table()->get("order")), field + ".order",
                             "must be odd and not a multiple of 3 (even and triplen harmonics do not reach a star-connected machine's currents)");
        harmonic.amplitude = h.number("amplitude", 0.0, 0.0, 0.5);
        harmonic.phase = h.number("phase", 0.0, -std::numbers::pi, std::numbers::pi);
        harmonics.push_back(harmonic);
    }
    return rotor;
}

ThermalNetwork read_thermal_network(const std::string& file, const toml::table& plant) {
    ThermalNetwork n;
    if (!plant.get("thermal")) return n;
    TableReader r(file, device_subtable(file, plant, "thermal"), "plant.thermal", 0);
    r.allow_only({"enabled", "winding_capacity", "magnet_capacity", "winding_to_magnet", "winding_to_ambient",
                  "magnet_to_ambient", "ambient", "initial_winding", "initial_magnet", "iron_loss", "alpha_magnet"});
    n.enabled = r.boolean("enabled", true);
    n.winding_capacity = r.number("winding_capacity", n.winding_capacity, 0.0, 1e9, true);
    n.magnet_capacity = r.number("magnet_capacity", n.magnet_capacity, 0.0, 1e9, true);
    n.winding_to_magnet = r.number("winding_to_magnet", n.winding_to_magnet, 0.0, 1e9, true);
    n.winding_to_ambient = r.number("winding_to_ambient", n.winding_to_ambient, 0.0, 1e9, true);
    n.magnet_to_ambient = r.number("magnet_to_ambient", n.magnet_to_ambient, 0.0, 1e9, true);
    n.ambient = r.number("ambient", n.ambient, -273.15, 1000.0);
    n.initial_winding = r.number("initial_winding", n.ambient, -273.15, 1000.0);
    n.initial_magnet = r.number("initial_magnet", n.ambient, -273.15, 1000.0);
    n.iron_loss = r.number("iron_loss", n.iron_loss, 0.0, 1e6);
    n.alpha_magnet = r.number("alpha_magnet", n.alpha_magnet, -0.01, 0.01);
    return n;
}

// Reads [plant]; with model = "device" the effect library and prescribed temperatures are refused
// (one plant or the other).
std::optional<DeviceSettings> read_plant(const std::string& file, const toml::table& root, double control_period) {
    const toml::node* node = root.get("plant");
    if (!node) return std::nullopt;
    if (!node->is_table()) throw InputError(file, line_of(*node), "plant", "expects a table");
    const toml::table& plant = *node->as_table();
    std::string model = "averaged";
    if (const toml::node* m = plant.get("model")) {
        if (!m->is_string() || (m->value<std::string>() != "averaged" && m->value<std::string>() != "device"))
            throw InputError(file, line_of(*m), "plant.model", "expects \"averaged\" or \"device\"");
        model = m->value<std::string>().value();
    }
    TableReader top(file, plant, "plant", line_of(*node));
    if (model == "averaged") {
        top.allow_only({"model"});
        return std::nullopt;
    }
    top.allow_only({"model", "inverter", "encoder", "rotor_flux", "saturation", "current_sensors", "thermal", "logging_offset"});
    for (const char* library : {"effects", "temperature"})
        if (const toml::node* n = root.get(library))
            throw InputError(file, line_of(*n), library,
                             std::string(library) == "effects"
                                 ? "library effects act on the averaged plant; with plant.model = \"device\" the drive's "
                                   "imperfections are device settings ([plant.inverter], [plant.encoder], ...)"
                                 : "with plant.model = \"device\" the temperatures come from [plant.thermal] (its "
                                   "network, or initial_winding/initial_magnet held with enabled = false)");
    DeviceSettings d;
    d.inverter = read_inverter(file, plant, control_period);
    {
        TableReader r(file, device_subtable(file, plant, "encoder"), "plant.encoder", 0);
        r.allow_only({"lines", "offset"});
        d.encoder.lines = r.integer("lines", 0, 0, 1'000'000'000);
        d.encoder.offset = r.number("offset", 0.0, -std::numbers::pi, std::numbers::pi);
    }
    d.rotor_flux = read_rotor_flux(file, plant);
    {
        TableReader r(file, device_subtable(file, plant, "saturation"), "plant.saturation", 0);
        r.allow_only({"saturation_current"});
        d.saturation.saturation_current = r.number("saturation_current", 0.0, 0.0, 1e6);
    }
    {
        TableReader r(file, device_subtable(file, plant, "current_sensors"), "plant.current_sensors", 0);
        r.allow_only({"offset_a", "offset_b", "gain_a", "gain_b"});
        d.current_sensors.offset_a = r.number("offset_a", 0.0, -1e3, 1e3);
        d.current_sensors.offset_b = r.number("offset_b", 0.0, -1e3, 1e3);
        d.current_sensors.gain_a = r.number("gain_a", 1.0, 0.0, 10.0, true);
        d.current_sensors.gain_b = r.number("gain_b", 1.0, 0.0, 10.0, true);
    }
    d.thermal = read_thermal_network(file, plant);
    {
        TableReader r(file, device_subtable(file, plant, "logging_offset"), "plant.logging_offset", 0);
        r.allow_only({"u_d", "u_q"});
        d.logging_offset.u_d = r.number("u_d", 0.0, -1e3, 1e3);
        d.logging_offset.u_q = r.number("u_q", 0.0, -1e3, 1e3);
    }
    return d;
}

// The device settings as the sidecar records them (the truth of a device-plant record).
nlohmann::ordered_json device_sidecar(const DeviceSettings& d) {
    using json = nlohmann::ordered_json;
    json harmonics = json::array();
    for (const auto& h : d.rotor_flux.harmonics) harmonics.push_back({{"order", h.order}, {"amplitude", h.amplitude}, {"phase", h.phase}});
    const auto& inv = d.inverter;
    const auto& th = d.thermal;
    const auto& cs = d.current_sensors;
    return {{"model", "device"},
            {"inverter", {{"pwm_frequency", inv.pwm_frequency}, {"dead_time", inv.dead_time}, {"switch_drop", inv.switch_drop},
                          {"diode_drop", inv.diode_drop}, {"switch_resistance", inv.switch_resistance},
                          {"diode_resistance", inv.diode_resistance}, {"delay_compensation", inv.delay_compensation}}},
            {"encoder", {{"lines", d.encoder.lines}, {"offset", d.encoder.offset}}},
            {"rotor_flux", {{"harmonics", harmonics}, {"eccentricity", d.rotor_flux.eccentricity},
                            {"eccentricity_phase", d.rotor_flux.eccentricity_phase}}},
            {"saturation", {{"saturation_current", d.saturation.saturation_current}}},
            {"current_sensors", {{"offset_a", cs.offset_a}, {"offset_b", cs.offset_b}, {"gain_a", cs.gain_a}, {"gain_b", cs.gain_b}}},
            {"thermal", {{"enabled", th.enabled}, {"winding_capacity", th.winding_capacity}, {"magnet_capacity", th.magnet_capacity},
                         {"winding_to_magnet", th.winding_to_magnet}, {"winding_to_ambient", th.winding_to_ambient},
                         {"magnet_to_ambient", th.magnet_to_ambient}, {"ambient", th.ambient},
                         {"initial_winding", th.initial_winding}, {"initial_magnet", th.initial_magnet},
                         {"iron_loss", th.iron_loss}, {"alpha_copper", copper_temperature_coefficient},
                         {"alpha_magnet", th.alpha_magnet}}},
            {"logging_offset", {{"u_d", d.logging_offset.u_d}, {"u_q", d.logging_offset.u_q}}}};
}

}  // namespace

DriveSimulation parse_simulation_profile(const std::string& text, const std::string& source,
                                         const std::filesystem::path& base_directory) {
    toml::table root;
    try {
        root = toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        throw InputError(source, static_cast<long>(e.source().begin.line), "", std::string(e.description()));
    }
    const std::string& file = source;
    TableReader top(file, root, "", 0);
    top.allow_only({"motor", "mechanics", "drive", "logging", "noise", "temperature", "effects", "plant", "segment"});

    DriveSimulation sim;
    sim.base_directory = base_directory;
    {
        TableReader r(file, subtable(file, root, "motor"), "motor", 0);
        r.allow_only({"rs", "ld", "lq", "psi_f", "pole_pairs"});
        sim.motor.rs = r.number("rs", sim.motor.rs, 0.0, 1e6, true);
        sim.motor.ld = r.number("ld", sim.motor.ld, 0.0, 1e3, true);
        sim.motor.lq = r.number("lq", sim.motor.lq, 0.0, 1e3, true);
        sim.motor.psi_f = r.number("psi_f", sim.motor.psi_f, 0.0, 1e3, true);
        sim.motor.pole_pairs = static_cast<int>(r.integer("pole_pairs", sim.motor.pole_pairs, 1, 1000));
    }
    {
        TableReader r(file, subtable(file, root, "mechanics"), "mechanics", 0);
        r.allow_only({"motor_inertia", "load_inertia", "gear_ratio", "viscous_friction"});
        sim.mechanics.motor_inertia = r.number("motor_inertia", sim.mechanics.motor_inertia, 0.0, 1e6, true);
        sim.mechanics.load_inertia = r.number("load_inertia", sim.mechanics.load_inertia, 0.0, 1e9);
        sim.mechanics.gear_ratio = r.number("gear_ratio", sim.mechanics.gear_ratio, 0.0, 1e6, true);
        sim.mechanics.viscous_friction = r.number("viscous_friction", sim.mechanics.viscous_friction, 0.0, 1e6);
    }
    long control_line = 0, step_line = 0;
    {
        const auto& t = subtable(file, root, "drive");
        TableReader r(file, t, "drive", 0);
        r.allow_only({"dc_voltage", "control_period", "integration_step", "current_bandwidth", "speed_bandwidth",
                      "position_gain", "current_limit"});
        auto& c = sim.control;
        c.dc_voltage = r.number("dc_voltage", c.dc_voltage, 0.0, 1e6, true);
        c.control_period = r.number("control_period", c.control_period, 0.0, 1.0, true);
        c.integration_step = r.number("integration_step", c.integration_step, 0.0, 1.0, true);
        c.current_bandwidth = r.number("current_bandwidth", c.current_bandwidth, 0.0, 1e6, true);
        c.speed_bandwidth = r.number("speed_bandwidth", c.speed_bandwidth, 0.0, 1e5, true);
        c.position_gain = r.number("position_gain", c.position_gain, 0.0, 1e5);
        c.current_limit = r.number("current_limit", c.current_limit, 0.0, 1e6, true);
        if (const auto* n = t.get("control_period")) control_line = line_of(*n);
        if (const auto* n = t.get("integration_step")) step_line = line_of(*n);
    }
    long period_line = 0;
    {
        const auto& t = subtable(file, root, "logging");
        TableReader r(file, t, "logging", 0);
        r.allow_only({"period", "filter_cutoff", "theta", "theta_m", "time", "temperatures", "transients", "segment"});
        auto& l = sim.logging;
        l.period = r.number("period", l.period, 0.0, 1e3, true);
        l.filter_cutoff = r.number("filter_cutoff", l.filter_cutoff, 0.0, 1e9);
        l.theta = r.boolean("theta", l.theta);
        l.shaft_angle = r.boolean("theta_m", l.shaft_angle);
        l.time = r.boolean("time", l.time);
        l.transients = r.boolean("transients", l.transients);
        l.segment = r.boolean("segment", l.segment);
        if (const auto* n = t.get("period")) period_line = line_of(*n);
    }
    // Grids: the plant steps must tile a control period, control periods a logging period.
    auto whole = [&](double a, double b, long line, const char* field, const char* ratio_name) {
        const double ratio = a / b;
        if (std::llround(ratio) < 1 || std::abs(ratio - static_cast<double>(std::llround(ratio))) > 1e-6 * ratio)
            throw InputError(file, line, field, fmt::format("{} = {} must be a whole number >= 1", ratio_name, ratio));
    };
    whole(sim.control.control_period, sim.control.integration_step, step_line ? step_line : control_line,
          step_line ? "drive.integration_step" : "drive.control_period", "control_period / integration_step");
    whole(sim.logging.period, sim.control.control_period, period_line ? period_line : control_line,
          period_line ? "logging.period" : "drive.control_period", "logging.period / control_period");
    sim.device = read_plant(file, root, sim.control.control_period);
    {
        TableReader r(file, subtable(file, root, "noise"), "noise", 0);
        r.allow_only({"seed", "current", "speed", "voltage", "temperature"});
        sim.seed = static_cast<std::uint64_t>(r.integer("seed", 0, 0, std::numeric_limits<std::int64_t>::max()));
        sim.noise.current = r.number("current", 0.0, 0.0, 1e6);
        sim.noise.speed = r.number("speed", 0.0, 0.0, 1e6);
        sim.noise.voltage = r.number("voltage", 0.0, 0.0, 1e6);
        sim.noise.temperature = r.number("temperature", 0.0, 0.0, 1e6);
    }
    const bool has_temperature = root.get("temperature") != nullptr;
    {
        TableReader r(file, subtable(file, root, "temperature"), "temperature", 0);
        r.allow_only({"winding", "magnet"});
        sim.temp_winding = read_temperature(r, "winding");
        sim.temp_magnet = read_temperature(r, "magnet");
    }
    bool thermal = false;
    for (auto&& [key, node] : subtable(file, root, "effects")) {
        bool enabled = true;
        auto effect = read_effect(file, std::string(key.str()), node, enabled);
        if (!enabled) continue;
        thermal = thermal || effect->name() == "rs_thermal" || effect->name() == "psi_thermal";
        sim.effects.push_back(std::move(effect));
    }
    {
        TableReader r(file, subtable(file, root, "logging"), "logging", 0);
        const bool device_thermal = sim.device && sim.device->thermal.enabled;
        sim.logging.temperatures = r.boolean("temperatures", has_temperature || thermal || device_thermal);
    }
    const toml::node* segments = root.get("segment");
    if (!segments) throw InputError(file, 0, "segment", "a profile needs at least one [[segment]]");
    const toml::array* list = segments->as_array();
    if (!list || list->empty()) throw InputError(file, line_of(*segments), "segment", "expects an array of tables [[segment]]");
    std::int64_t total_samples = 0;
    for (std::size_t k = 0; k < list->size(); ++k) {
        sim.segments.push_back(read_segment(file, (*list)[k], k, sim.logging.period));
        total_samples += sim.segments.back().samples;
        if (sim.logging.transients)
            total_samples += std::llround(sim.segments.back().settle / sim.control.control_period) /
                             std::llround(sim.logging.period / sim.control.control_period);
        // Checked before anything is simulated: the whole measurement is held in memory and written as one CSV.
        if (total_samples > max_measurement_rows)
            throw InputError(file, line_of((*list)[k]), fmt::format("segment[{}]", k + 1),
                             fmt::format("the segments up to here ask for {} samples; the limit is {} per profile "
                                         "(a measurement file holds at most that many rows)", total_samples, max_measurement_rows));
    }
    return sim;
}

DriveSimulation read_simulation_profile(const std::filesystem::path& path) {
    return parse_simulation_profile(read_text_file(path, "simulation profile"), path.string(), path.parent_path());
}

std::filesystem::path sidecar_path(const std::filesystem::path& csv) {
    std::filesystem::path p = csv;
    return p.replace_extension(".json");
}

nlohmann::ordered_json simulation_sidecar(const DriveSimulation& spec, const SimulationResult& result,
                                          const std::string& profile) {
    using json = nlohmann::ordered_json;
    json j;
    j["generator"] = "mhbench simulate";
    j["profile"] = profile;
    j["seed"] = spec.seed;
    j["samples"] = result.data.size();
    j["simulated_time"] = result.simulated_time;
    std::string flux_map;
    for (const auto& e : spec.effects)
        if (e->settings().contains("flux_map")) flux_map = e->settings().text("flux_map");
    if (flux_map.empty()) {
        j["true_parameters"] = {{"Rs", spec.motor.rs}, {"Ld", spec.motor.ld}, {"Lq", spec.motor.lq}, {"psi_f", spec.motor.psi_f}};
        if (spec.device && spec.device->saturation.saturation_current > 0)
            j["true_parameters_note"] = "the plant's iron saturates (plant.saturation): Ld and Lq are its small-current inductances";
    } else {
        j["plant_flux_map"] = flux_map;
        j["true_parameters_note"] = "the plant is a measured flux map: Ld, Lq and psi_f have no single true value; "
                                    "motor gives the controller's nominal parameters";
    }
    j["reference_temperature"] = reference_temperature;
    j["motor"] = {{"rs", spec.motor.rs}, {"ld", spec.motor.ld}, {"lq", spec.motor.lq}, {"psi_f", spec.motor.psi_f},
                  {"pole_pairs", spec.motor.pole_pairs}};
    j["mechanics"] = {{"motor_inertia", spec.mechanics.motor_inertia}, {"load_inertia", spec.mechanics.load_inertia},
                      {"gear_ratio", spec.mechanics.gear_ratio}, {"viscous_friction", spec.mechanics.viscous_friction},
                      {"total_inertia", spec.mechanics.total_inertia()}};
    const auto& c = spec.control;
    j["drive"] = {{"dc_voltage", c.dc_voltage}, {"control_period", c.control_period}, {"integration_step", c.integration_step},
                  {"current_bandwidth", c.current_bandwidth}, {"speed_bandwidth", c.speed_bandwidth},
                  {"position_gain", c.position_gain}, {"current_limit", c.current_limit}};
    j["logging"] = {{"period", spec.logging.period}, {"filter_cutoff", spec.logging.filter_cutoff},
                    {"theta", spec.logging.theta}, {"time", spec.logging.time}, {"temperatures", spec.logging.temperatures}};
    // Written only when logged, so that the sidecars of profiles that never log it stay as they were.
    if (spec.logging.shaft_angle) j["logging"]["theta_m"] = true;
    if (spec.logging.transients) j["logging"]["transients"] = true;
    if (!spec.logging.segment) j["logging"]["segment"] = false;
    j["noise"] = {{"current", spec.noise.current}, {"speed", spec.noise.speed}, {"voltage", spec.noise.voltage},
                  {"temperature", spec.noise.temperature}};
    auto points = [](const TemperatureProfile& p) {
        json a = json::array();
        for (const auto& [t, temp] : p.points) a.push_back({t, temp});
        return a;
    };
    j["temperature"] = {{"winding", points(spec.temp_winding)}, {"magnet", points(spec.temp_magnet)}};
    json effects = json::array();
    for (const auto& e : spec.effects) {
        json parameters = json::object();
        // A named copy, not the structured binding: clang 14 cannot capture a binding in a lambda.
        for (const auto& entry : e->settings().values()) {
            const std::string& name = entry.first;
            std::visit([&](const auto& v) { parameters[name] = v; }, entry.second);
        }
        effects.push_back({{"name", e->name()}, {"parameters", parameters}});
    }
    j["effects"] = effects;
    if (spec.device) j["plant"] = device_sidecar(*spec.device);
    json segments = json::array();
    for (std::size_t k = 0; k < spec.segments.size(); ++k) {
        const auto& s = spec.segments[k];
        segments.push_back({{"label", s.label}, {"speed_rpm", s.speed_rpm}, {"load_torque", s.load_torque}, {"i_d", s.i_d},
                            {"settle", s.settle}, {"samples", s.samples}, {"first_row", result.segments[k].first_row},
                            {"start_time", result.segments[k].start_time}});
        // The raw log's truth for finding operating points: where each segment's settling is logged.
        if (spec.logging.transients) segments.back()["settle_first_row"] = result.segments[k].settle_first_row;
    }
    j["segments"] = segments;
    return j;
}

void write_simulation(const std::filesystem::path& csv, const DriveSimulation& spec, const SimulationResult& result,
                      const std::string& profile) {
    write_measurement(csv, result.data);
    const auto json_path = sidecar_path(csv);
    std::ofstream out(json_path, std::ios::binary);
    if (!out) throw InputError(json_path.string(), 0, "", "cannot open the file for writing");
    out << simulation_sidecar(spec, result, profile).dump(2) << '\n';
    if (!out) throw InputError(json_path.string(), 0, "", "write failed");
}

std::optional<Eigen::Vector4d> read_sidecar_truth(const std::filesystem::path& csv) {
    const auto path = sidecar_path(csv);
    if (!std::filesystem::exists(path)) return std::nullopt;
    const std::string text = read_text_file(path, "sidecar");
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        const long line = 1 + static_cast<long>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(
                                                                                 std::min<std::size_t>(e.byte, text.size())), '\n'));
        throw InputError(path.string(), line, "", "not valid JSON");
    }
    if (!j.contains("true_parameters")) return std::nullopt;
    const auto& t = j["true_parameters"];
    Eigen::Vector4d truth;
    for (int k = 0; k < 4; ++k) {
        const auto& name = base_parameter_names[static_cast<std::size_t>(k)];
        if (!t.contains(name) || !t[name].is_number())
            throw InputError(path.string(), 0, "true_parameters." + name, "missing or not a number");
        truth[k] = t[name].get<double>();
    }
    return truth;
}

}  // namespace mhb::pmsm
