// The worked example of docs/writing-an-effect.md is a real plugin (docs/examples/slot_harmonic.cpp,
// compiled into this binary): the page shows exactly that file, and the effect does what the page says.
#include <catch2/catch.hpp>

#include <complex>
#include <fstream>
#include <numbers>

#include "problems/pmsm/effects/effect.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {
std::string read(const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST_CASE("the page shows the example file verbatim", "[writing_an_effect]") {
    const std::string source = read(std::string(MHBENCH_SOURCE_DIR) + "/docs/examples/slot_harmonic.cpp");
    const std::string page = read(std::string(MHBENCH_SOURCE_DIR) + "/docs/writing-an-effect.md");
    REQUIRE(source.size() > 1000);
    REQUIRE(page.find("```cpp\n" + source + "```\n") != std::string::npos);
}

TEST_CASE("the example effect registers and adds a pure 12th harmonic of the angle", "[writing_an_effect]") {
    const auto effect = make_effect("slot_harmonic");
    REQUIRE(effect->parameter_names() == std::vector<std::string>{"h11", "phi11", "h13", "phi13"});
    REQUIRE(effect->model_columns() == std::vector<std::string>{"theta_e"});
    const Eigen::Index n = 720;
    ModelState state;
    state.resize(n);
    state.theta.resize(n);  // resize() sizes theta only for data with a theta_e column
    for (Eigen::Index k = 0; k < n; ++k) state.theta[k] = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(n);
    state.omega.setConstant(100.0);
    state.psi_f.setConstant(0.05);
    state.u_d.setZero();
    state.u_q.setZero();
    const double p[] = {0.01, 0.3, 0.004, -1.1};
    effect->model(ModelStage::MachineVoltage, p, state);
    // Fourier coefficients of u_d + j u_q over one electrical turn: the 11th harmonic turns at -12
    // and the 13th at +12 in the rotor frame, so |order| = 12 and nothing else.
    double at12 = 0, elsewhere = 0;
    for (int order = -20; order <= 20; ++order) {
        std::complex<double> c = 0;
        for (Eigen::Index k = 0; k < n; ++k)
            c += std::complex<double>(state.u_d[k], state.u_q[k]) * std::polar(1.0, -order * state.theta[k]);
        const double amplitude = std::abs(c) / static_cast<double>(n);
        if (std::abs(order) == 12) at12 += amplitude;
        else elsewhere += amplitude;
    }
    // EMF amplitudes omega psi_f 11 h11 and omega psi_f 13 h13.
    REQUIRE(at12 == Approx(100.0 * 0.05 * (11 * 0.01 + 13 * 0.004)).epsilon(1e-9));
    REQUIRE(elsewhere < 1e-12);
}
