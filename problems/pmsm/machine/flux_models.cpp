#include "problems/pmsm/machine/flux_models.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {
namespace {

std::size_t cell_index(const std::vector<double>& grid, double x) {
    const auto it = std::upper_bound(grid.begin(), grid.end(), x);
    const auto k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - grid.begin() - 1, 0));
    return std::min(k, grid.size() - 2);
}

}  // namespace

FluxMap::FluxMap(std::vector<double> i_d, std::vector<double> i_q, std::vector<double> psi_d,
                 std::vector<double> psi_q, double nominal_psi_f)
    : i_d_(std::move(i_d)), i_q_(std::move(i_q)), psi_d_(std::move(psi_d)), psi_q_(std::move(psi_q)),
      nominal_psi_f_(nominal_psi_f), magnet_flux_(0.0) {
    if (i_d_.size() < 2 || i_q_.size() < 2 || psi_d_.size() != i_d_.size() * i_q_.size() || psi_q_.size() != psi_d_.size())
        throw std::invalid_argument("flux map: needs at least a 2 x 2 grid with one flux pair per point");
    if (!(nominal_psi_f > 0.0)) throw std::invalid_argument("flux map: the nominal magnet flux must be positive");
    magnet_flux_ = FluxMap::flux(Complex{0.0, 0.0}, nominal_psi_f_).real();
}

FluxMap::Cell FluxMap::locate(Complex i) const {
    const std::size_t a = cell_index(i_d_, i.real()), b = cell_index(i_q_, i.imag());
    return {a, b, (i.real() - i_d_[a]) / (i_d_[a + 1] - i_d_[a]), (i.imag() - i_q_[b]) / (i_q_[b + 1] - i_q_[b])};
}

Complex FluxMap::flux(Complex i, double psi_f) const {
    const Cell c = locate(i);
    auto interpolate = [&](const std::vector<double>& t) {
        return (1 - c.u) * (1 - c.v) * at(t, c.a, c.b) + c.u * (1 - c.v) * at(t, c.a + 1, c.b) +
               (1 - c.u) * c.v * at(t, c.a, c.b + 1) + c.u * c.v * at(t, c.a + 1, c.b + 1);
    };
    // magnet_flux_ is still 0 while the constructor measures it, which makes this the raw map there.
    return {interpolate(psi_d_) + (psi_f / nominal_psi_f_ - 1.0) * magnet_flux_, interpolate(psi_q_)};
}

Inductance FluxMap::incremental_inductance(Complex i) const {
    const Cell c = locate(i);
    const double hd = i_d_[c.a + 1] - i_d_[c.a], hq = i_q_[c.b + 1] - i_q_[c.b];
    auto gradient = [&](const std::vector<double>& t) {
        const double f00 = at(t, c.a, c.b), f10 = at(t, c.a + 1, c.b), f01 = at(t, c.a, c.b + 1),
                     f11 = at(t, c.a + 1, c.b + 1);
        return std::array<double, 2>{((1 - c.v) * (f10 - f00) + c.v * (f11 - f01)) / hd,
                                     ((1 - c.u) * (f01 - f00) + c.u * (f11 - f10)) / hq};
    };
    const auto gd = gradient(psi_d_), gq = gradient(psi_q_);
    return {gd[0], gd[1], gq[0], gq[1]};
}

FluxMap FluxMap::read(const std::filesystem::path& path, double nominal_psi_f) {
    return parse(read_text_file(path, "flux map"), path.string(), nominal_psi_f);
}

FluxMap FluxMap::parse(const std::string& text, const std::string& file, double nominal_psi_f) {

    // Same CSV conventions as measurements (header row, commas, SI units); the columns differ.
    std::vector<std::string> lines;
    std::istringstream stream(text);
    for (std::string line; std::getline(stream, line);) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        lines.push_back(line);
    }
    if (lines.empty()) throw InputError(file, 0, "", "empty file");
    auto split = [](const std::string& line) {
        std::vector<std::string> out;
        std::string field;
        std::istringstream s(line);
        while (std::getline(s, field, ',')) {
            const auto b = field.find_first_not_of(" \t"), e = field.find_last_not_of(" \t");
            out.push_back(b == std::string::npos ? std::string() : field.substr(b, e - b + 1));
        }
        if (!line.empty() && line.back() == ',') out.emplace_back();
        return out;
    };
    const auto header = split(lines[0]);
    const char* names[] = {"i_d_A", "i_q_A", "psi_d_Vs", "psi_q_Vs"};
    std::size_t column[4];
    for (int k = 0; k < 4; ++k) {
        const auto it = std::find(header.begin(), header.end(), names[k]);
        if (it == header.end()) throw InputError(file, 1, names[k], "missing column in the flux map");
        column[k] = static_cast<std::size_t>(it - header.begin());
    }
    std::map<std::pair<double, double>, std::pair<double, double>> points;
    std::map<std::pair<double, double>, long> point_line;
    for (std::size_t l = 1; l < lines.size(); ++l) {
        const long line_no = static_cast<long>(l + 1);
        if (lines[l].find_first_not_of(" \t") == std::string::npos) continue;
        const auto fields = split(lines[l]);
        if (fields.size() != header.size())
            throw InputError(file, line_no, "", fmt::format("row has {} fields but the header has {}", fields.size(), header.size()));
        double v[4];
        for (int k = 0; k < 4; ++k) {
            const auto& f = fields[column[k]];
            const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), v[k]);
            if (ec != std::errc() || ptr != f.data() + f.size() || !std::isfinite(v[k]))
                throw InputError(file, line_no, names[k], fmt::format("not a finite number: '{}'", f));
        }
        const std::pair<double, double> key{v[0] + 0.0, v[1] + 0.0};  // + 0.0 folds -0 into 0
        if (auto it = point_line.find(key); it != point_line.end())
            throw InputError(file, line_no, "", fmt::format("grid point ({}, {}) A repeats line {}", v[0], v[1], it->second));
        points[key] = {v[2], v[3]};
        point_line[key] = line_no;
    }
    std::vector<double> grid_d, grid_q;
    for (const auto& [key, value] : points) {
        grid_d.push_back(key.first);
        grid_q.push_back(key.second);
    }
    std::sort(grid_d.begin(), grid_d.end());
    grid_d.erase(std::unique(grid_d.begin(), grid_d.end()), grid_d.end());
    std::sort(grid_q.begin(), grid_q.end());
    grid_q.erase(std::unique(grid_q.begin(), grid_q.end()), grid_q.end());
    for (const auto& [axis, grid] : {std::pair{"i_d_A", &grid_d}, std::pair{"i_q_A", &grid_q}})
        if (grid->size() < 2)
            throw InputError(file, 0, axis, fmt::format("a flux map needs at least two values of this current to interpolate between; "
                                                        "it has only {} A", grid->front()));
    for (double d : grid_d)
        for (double q : grid_q)
            if (!points.count({d, q}))
                throw InputError(file, 0, "", fmt::format("the grid lacks the point (i_d, i_q) = ({}, {}) A: a flux map is a complete "
                                                          "rectangular grid ({} points given for {} i_d x {} i_q values)",
                                                          d, q, points.size(), grid_d.size(), grid_q.size()));
    // Each axis' flux must rise with its own current (a positive incremental inductance): a map that
    // falls somewhere is mislabelled or has a sign error, and the plant's Newton inversion of it would
    // have no unique answer there.
    auto check_rising = [&](const char* field, double psi_of(const std::pair<double, double>&), bool along_d) {
        const auto& outer = along_d ? grid_q : grid_d;
        const auto& inner = along_d ? grid_d : grid_q;
        for (double o : outer)
            for (std::size_t k = 1; k < inner.size(); ++k) {
                const std::pair<double, double> before = along_d ? std::pair{inner[k - 1], o} : std::pair{o, inner[k - 1]};
                const std::pair<double, double> here = along_d ? std::pair{inner[k], o} : std::pair{o, inner[k]};
                const double a = psi_of(points.at(before)), b = psi_of(points.at(here));
                if (!(b > a))
                    throw InputError(file, point_line.at(here), field,
                                     fmt::format("{} {} from {} Wb at {} = {} A to {} Wb at {} = {} A ({} = {} A): the flux of an axis "
                                                 "must rise with its own current", along_d ? "psi_d" : "psi_q", b == a ? "stays" : "falls",
                                                 a, along_d ? "i_d" : "i_q", inner[k - 1], b, along_d ? "i_d" : "i_q", inner[k],
                                                 along_d ? "i_q" : "i_d", o));
            }
    };
    check_rising("psi_d_Vs", [](const std::pair<double, double>& p) { return p.first; }, true);
    check_rising("psi_q_Vs", [](const std::pair<double, double>& p) { return p.second; }, false);
    std::vector<double> psi_d, psi_q;
    for (double d : grid_d)
        for (double q : grid_q) {
            const auto& p = points.at({d, q});
            psi_d.push_back(p.first);
            psi_q.push_back(p.second);
        }
    return FluxMap(std::move(grid_d), std::move(grid_q), std::move(psi_d), std::move(psi_q), nominal_psi_f);
}

}  // namespace mhb::pmsm
