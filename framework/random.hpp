#pragma once
// Random numbers for trials: a fast generator whose whole stream is fixed by one 64-bit seed, and the
// derivation of each trial's seed from the experiment's master seed, so results do not depend on the
// order or the thread in which trials run.
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <string_view>

namespace mhb {

// SplitMix64 (Steele, Lea, Flood 2014): used to expand one seed into generator state and to mix
// seed components; consecutive inputs give statistically independent outputs.
constexpr std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

// FNV-1a: a hash that is the same on every platform and run (std::hash is not), so a seed derived
// from a name is reproducible.
constexpr std::uint64_t stable_hash(std::string_view text) {
    std::uint64_t h = 0xCBF29CE484222325ULL;
    for (unsigned char c : text) {
        h ^= c;
        h *= 0x100000001B3ULL;
    }
    return h;
}

// Seed of one trial from (master seed, optimiser label, problem label, trial index).
constexpr std::uint64_t derive_seed(std::uint64_t master, std::string_view optimizer,
                                    std::string_view problem, std::uint64_t trial) {
    std::uint64_t state = master;
    std::uint64_t s = splitmix64(state);
    for (std::uint64_t part : {stable_hash(optimizer), stable_hash(problem), trial}) {
        state = s ^ part;
        s = splitmix64(state);
    }
    return s;
}

// xoshiro256++ (Blackman & Vigna 2019): small state, fast, passes BigCrush; satisfies
// UniformRandomBitGenerator so it also works with <random> distributions.
class Rng {
public:
    using result_type = std::uint64_t;
    explicit Rng(std::uint64_t seed = 0) { reseed(seed); }

    void reseed(std::uint64_t seed) {
        std::uint64_t sm = seed;
        for (auto& word : s_) word = splitmix64(sm);
        has_spare_normal_ = false;
    }
    // The raw 256-bit state, as in the reference implementation's s[0..3] (must not be all zero);
    // for checking against published output streams.
    void set_state(std::uint64_t s0, std::uint64_t s1, std::uint64_t s2, std::uint64_t s3) {
        s_[0] = s0;
        s_[1] = s1;
        s_[2] = s2;
        s_[3] = s3;
        has_spare_normal_ = false;
    }
    static constexpr result_type min() { return 0; }
    static constexpr result_type max() { return ~result_type{0}; }

    result_type operator()() {
        const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
        const std::uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }

    // Uniform on [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>((*this)() >> 11) * 0x1.0p-53; }
    // Uniform on (0, 1): for transforms that take a logarithm or a reciprocal.
    double uniform_open() { return (static_cast<double>((*this)() >> 11) + 0.5) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

    // Uniform integer in [0, n), n > 0, without modulo bias (Lemire 2019).
    std::uint64_t below(std::uint64_t n) {
        __uint128_t m = static_cast<__uint128_t>((*this)()) * n;
        auto low = static_cast<std::uint64_t>(m);
        if (low < n) {
            const std::uint64_t threshold = (0 - n) % n;
            while (low < threshold) {
                m = static_cast<__uint128_t>((*this)()) * n;
                low = static_cast<std::uint64_t>(m);
            }
        }
        return static_cast<std::uint64_t>(m >> 64);
    }

    // Standard normal by the Marsaglia polar method; the second value of each pair is kept.
    double normal() {
        if (has_spare_normal_) {
            has_spare_normal_ = false;
            return spare_normal_;
        }
        double u, v, s;
        do {
            u = 2.0 * uniform() - 1.0;
            v = 2.0 * uniform() - 1.0;
            s = u * u + v * v;
        } while (s >= 1.0 || s == 0.0);
        const double factor = std::sqrt(-2.0 * std::log(s) / s);
        spare_normal_ = v * factor;
        has_spare_normal_ = true;
        return u * factor;
    }
    double normal(double mean, double sd) { return mean + sd * normal(); }

    // Cauchy(location, scale) by inversion.
    double cauchy(double location, double scale) {
        return location + scale * std::tan(std::numbers::pi * (uniform_open() - 0.5));
    }

    // +1 or -1 with equal probability.
    double sign() { return ((*this)() >> 63) ? 1.0 : -1.0; }

private:
    static constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t s_[4]{};
    double spare_normal_ = 0.0;
    bool has_spare_normal_ = false;
};

}  // namespace mhb
