#pragma once
// Immutable data that the problem instances of one experiment share: a measurement read from its
// file and the statistics computed from it. Problems are created once per trial (so a noisy
// problem owns its generator and evaluation stays lock-free); what they read and precompute is the
// same for every trial of a problem variant, so the first instance builds it and the others share
// it read-only for the experiment's lifetime.
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace mhb {

class SharedProblemData {
public:
    // The value stored under `key`, built by `build` the first time it is asked for. Concurrent
    // callers wait for that one build; a build that throws stores nothing and the next caller
    // tries again. Keys name everything the value depends on (file, parameters).
    template <class T>
    std::shared_ptr<const T> get(const std::string& key, const std::function<T()>& build) {
        std::lock_guard lock(mutex_);
        if (auto it = items_.find(key); it != items_.end()) return std::static_pointer_cast<const T>(it->second);
        auto value = std::make_shared<const T>(build());
        items_.emplace(key, value);
        ++builds_;
        return value;
    }
    // How many values were built (for tests and diagnostics).
    std::size_t builds() const {
        std::lock_guard lock(mutex_);
        return builds_;
    }

private:
    mutable std::mutex mutex_;
    std::map<std::string, std::shared_ptr<const void>> items_;
    std::size_t builds_ = 0;
};

}  // namespace mhb
