#pragma once
// Plugins (optimisers, problems, physical effects) register themselves from their own source file:
//
//   namespace { const bool registered = mhb::register_optimizer({
//       "gwo", "Grey wolf optimizer (Mirjalili 2014)", {ParameterSpec::integer("population", ...)},
//       [](const ParameterSet& p) { return std::make_unique<Gwo>(p); }}); }
//
// The build compiles every .cpp under optimizers/ and problems/ into an object library that is linked
// whole, so adding a plugin is adding one file; there is no central list to edit. A plugin built on
// its own registers the same way when the program loads it (framework/plugin_loader.hpp).
#include <algorithm>
#include <cctype>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/optimizer.hpp"
#include "framework/closest_name.hpp"
#include "framework/parameters.hpp"
#include "framework/problem.hpp"

namespace mhb {

// Thrown for a name that is not registered; the message lists the names that are.
class UnknownPlugin : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Where the registrations running now come from: "built-in" while the program starts, the library's
// path while framework/plugin_loader.cpp loads a plugin. A clash message names both origins.
const std::string& registration_origin();
void set_registration_origin(std::string origin);

// A second registration under a name already taken: it is kept aside, not used.
struct RegistrationClash {
    std::string name;
    std::string first_origin;   // the origin of the entry that keeps the name
    std::string second_origin;  // the origin of the one refused
    bool operator==(const RegistrationClash&) const = default;
};
// "the optimizer 'gwo' of /p/libx.so clashes with the built-in optimizer 'gwo'; rename it"
std::string clash_message(const std::string& kind, const RegistrationClash& clash);

template <class Factory>
struct PluginEntry {
    std::string name;
    std::string summary;
    std::vector<ParameterSpec> parameters;
    Factory create;
};

template <class Factory>
class Registry {
public:
    using Entry = PluginEntry<Factory>;

    static Registry& instance() {
        static Registry registry;
        return registry;
    }

    // Returns true so that it can initialise a namespace-scope constant. A second entry under an
    // existing name is kept aside and reported by conflicts(): throwing here would terminate before
    // main() with no way to say which file is at fault.
    bool add(Entry entry) {
        const std::string key = fold(entry.name);
        if (auto it = origins_.find(key); it != origins_.end()) {
            conflicts_.push_back({entry.name, it->second, registration_origin()});
            return false;
        }
        origins_.emplace(key, registration_origin());
        entries_.emplace(key, std::move(entry));
        return true;
    }

    // Case-insensitive look-up; nullptr when absent.
    const Entry* find(const std::string& name) const {
        auto it = entries_.find(fold(name));
        return it == entries_.end() ? nullptr : &it->second;
    }

    const Entry& at(const std::string& name, const std::string& kind) const {
        if (const Entry* e = find(name)) return *e;
        std::vector<std::string> known;
        for (const Entry* e : entries()) known.push_back(e->name);
        throw UnknownPlugin(unknown_name_message(kind, name, known));
    }

    // All entries, sorted by name (natural order, so F2 comes before F10).
    std::vector<const Entry*> entries() const {
        std::vector<const Entry*> out;
        for (const auto& [key, e] : entries_) out.push_back(&e);
        std::sort(out.begin(), out.end(), [](const Entry* a, const Entry* b) { return natural_less(a->name, b->name); });
        return out;
    }

    const std::vector<RegistrationClash>& conflicts() const { return conflicts_; }

    // "built-in" or the path of the plugin library that registered `name`; empty when absent.
    std::string origin(const std::string& name) const {
        auto it = origins_.find(fold(name));
        return it == origins_.end() ? std::string() : it->second;
    }

    // Removes an entry (tests register temporary plugins).
    void remove(const std::string& name) {
        entries_.erase(fold(name));
        origins_.erase(fold(name));
    }

private:
    static std::string fold(const std::string& s) {
        std::string out = s;
        for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return out;
    }
    static bool natural_less(const std::string& a, const std::string& b) {
        std::size_t i = 0, j = 0;
        while (i < a.size() && j < b.size()) {
            if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
                std::size_t i2 = i, j2 = j;
                while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
                while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
                const auto na = std::stoull(a.substr(i, i2 - i)), nb = std::stoull(b.substr(j, j2 - j));
                if (na != nb) return na < nb;
                i = i2;
                j = j2;
                continue;
            }
            const auto ca = std::tolower(static_cast<unsigned char>(a[i])), cb = std::tolower(static_cast<unsigned char>(b[j]));
            if (ca != cb) return ca < cb;
            ++i;
            ++j;
        }
        return a.size() - i < b.size() - j;
    }
    std::map<std::string, Entry> entries_;
    std::map<std::string, std::string> origins_;
    std::vector<RegistrationClash> conflicts_;
};

// Every registry that `mhbench list` shows and whose name conflicts it checks. Optimizers and
// problems are listed by the core; a plugin family with a registry of its own (e.g. the PMSM
// effects) adds itself with list_registry<Factory>("effects") from its own source file.
struct ListedRegistry {
    std::string kind;  // plural, e.g. "effects"
    std::function<std::vector<std::pair<std::string, std::string>>()> names_and_summaries;
    std::function<std::vector<std::vector<ParameterSpec>>()> parameters;  // in the same order
    std::function<std::vector<RegistrationClash>()> conflicts;
};
std::vector<ListedRegistry>& listed_registries();

// Every clash in every listed registry and among the commands, as one message each.
std::vector<std::string> registration_clashes();
// A registry that `mhbench list` does not show (the commands) adds its clashes to the above.
void add_clash_source(std::function<std::vector<std::string>()> source);

template <class Factory>
bool list_registry(const std::string& kind) {
    auto& reg = Registry<Factory>::instance();
    listed_registries().push_back(ListedRegistry{
        kind,
        [&reg] {
            std::vector<std::pair<std::string, std::string>> out;
            for (const auto* e : reg.entries()) out.emplace_back(e->name, e->summary);
            return out;
        },
        [&reg] {
            std::vector<std::vector<ParameterSpec>> out;
            for (const auto* e : reg.entries()) out.push_back(e->parameters);
            return out;
        },
        [&reg] { return reg.conflicts(); }});
    return true;
}

using OptimizerFactory = std::function<std::unique_ptr<Optimizer>(const ParameterSet&)>;
using ProblemFactory = std::function<std::unique_ptr<Problem>(const ParameterSet&, const ProblemContext&)>;

using OptimizerRegistry = Registry<OptimizerFactory>;
using ProblemRegistry = Registry<ProblemFactory>;

inline bool register_optimizer(PluginEntry<OptimizerFactory> entry) {
    return OptimizerRegistry::instance().add(std::move(entry));
}
inline bool register_problem(PluginEntry<ProblemFactory> entry) {
    return ProblemRegistry::instance().add(std::move(entry));
}

// Creates a plugin from its registry entry and user values (ParameterError on bad values).
std::unique_ptr<Optimizer> make_optimizer(const std::string& name,
                                          const std::map<std::string, ParameterValue>& values = {});
std::unique_ptr<Problem> make_problem(const std::string& name,
                                      const std::map<std::string, ParameterValue>& values = {},
                                      const ProblemContext& context = {});

}  // namespace mhb
