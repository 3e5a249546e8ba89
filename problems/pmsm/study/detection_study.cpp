#include "problems/pmsm/study/detection_study.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <toml++/toml.h>

#include "framework/input_error.hpp"
#include "framework/report_document.hpp"
#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/diagnosis/lack_of_fit.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"
#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {
namespace {

long line_of(const toml::node& n) { return static_cast<long>(n.source().begin.line); }

// Inline tables from the study file become ordinary ones, so the text reads as a profile section.
void expand_inline(toml::table& t) {
    t.is_inline(false);
    for (auto&& [key, node] : t)
        if (auto* sub = node.as_table()) expand_inline(*sub);
}

std::string toml_text(const toml::table& t) {
    toml::table copy = t;
    expand_inline(copy);
    std::ostringstream out;
    out << copy;
    return out.str();
}

std::string leaf_text(const toml::node& n) {
    toml::table wrapper;
    wrapper.insert("v", n);
    return toml_text(wrapper);
}

// Merges `from` into `into`, table by table; `from` wins. A leaf that `into` already holds with
// another value is reported to `conflict` (when given) by its dotted key: two imperfections of one
// case that set it differently.
void merge(toml::table& into, const toml::table& from, const std::string& prefix, const std::function<void(const std::string&)>& conflict) {
    for (auto&& [key, node] : from) {
        const std::string dotted = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
        toml::node* existing = into.get(key);
        if (existing && existing->is_table() && node.is_table()) {
            merge(*existing->as_table(), *node.as_table(), dotted, conflict);
        } else {
            if (existing && conflict && leaf_text(*existing) != leaf_text(node)) conflict(dotted);
            into.insert_or_assign(key, node);
        }
    }
}

// The text of `node` as the file writes it (from its source region), for tables people read.
std::string as_written(const std::string& text, const toml::node& node) {
    const auto& region = node.source();
    std::vector<std::size_t> line_start{0};
    for (std::size_t k = 0; k < text.size(); ++k)
        if (text[k] == '\n') line_start.push_back(k + 1);
    auto offset = [&](const toml::source_position& p) {
        const std::size_t line = std::clamp<std::size_t>(p.line, 1, line_start.size()) - 1;
        return std::min(text.size(), line_start[line] + (p.column > 0 ? p.column - 1 : 0));
    };
    const std::size_t begin = offset(region.begin), end = offset(region.end);
    return end > begin ? text.substr(begin, end - begin) : std::string();
}

toml::table parse_settings(const std::string& text, const std::string& source) {
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        throw InputError(source, static_cast<long>(e.source().begin.line), "", std::string(e.description()));
    }
}

const toml::table& settings_table(const std::string& file, const toml::table& t, std::string_view key, const std::string& field) {
    const toml::node* n = t.get(key);
    if (!n) throw InputError(file, 0, field + "." + std::string(key), "is required");
    if (!n->is_table()) throw InputError(file, line_of(*n), field + "." + std::string(key), "expects a table of profile settings, e.g. { effects.deadtime.voltage = 0.28 }");
    return *n->as_table();
}

std::string string_of(const std::string& file, const toml::node& n, const std::string& field) {
    if (!n.is_string()) throw InputError(file, line_of(n), field, "expects a string");
    return n.value<std::string>().value();
}

const toml::node& required(const std::string& file, const toml::table& t, std::string_view key, const std::string& field) {
    const toml::node* n = t.get(key);
    if (!n) throw InputError(file, line_of(t), field + "." + std::string(key), "is required");
    return *n;
}

// Calls `read` for each table of the array of tables `key` (absent: none), refusing unknown keys.
void each_table(const std::string& file, const toml::table& root, std::string_view key, const std::set<std::string>& allowed,
                const std::function<void(const std::string&, const toml::table&)>& read) {
    const toml::node* n = root.get(key);
    if (!n) return;
    const auto* list = n->as_array();
    if (!list) throw InputError(file, line_of(*n), std::string(key), fmt::format("expects [[{}]] tables", key));
    for (std::size_t k = 0; k < list->size(); ++k) {
        const std::string field = fmt::format("{}[{}]", key, k);
        const auto* t = (*list)[k].as_table();
        if (!t) throw InputError(file, line_of((*list)[k]), field, "expects a table");
        for (auto&& [name, node] : *t)
            if (!allowed.count(std::string(name.str())))
                throw InputError(file, line_of(node), field + "." + std::string(name.str()),
                                 "unknown key (allowed: " + fmt::format("{}", fmt::join(allowed, ", ")) + ")");
        read(field, *t);
    }
}

std::vector<std::string> name_list(const std::string& file, const toml::node& n, const std::string& field, std::size_t size,
                                   const std::set<std::string>& known) {
    const auto* a = n.as_array();
    if (!a || a->size() != size) throw InputError(file, line_of(n), field, fmt::format("expects a list of {} effect names", size));
    std::vector<std::string> out;
    for (const auto& e : *a) {
        const std::string name = string_of(file, e, field);
        if (!known.count(name)) throw InputError(file, line_of(e), field, "'" + name + "' is not one of the study's [[effect]] names");
        if (std::find(out.begin(), out.end(), name) != out.end()) throw InputError(file, line_of(e), field, "'" + name + "' named twice");
        out.push_back(name);
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string joined(const std::vector<std::string>& names, const char* separator) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : separator) + n;
    return out;
}

}  // namespace

namespace {

// `{ "deadtime.voltage" = 0.28 }`: each key a real parameter of `effect`, each value a finite number.
std::map<std::string, double> stated_sizes(const std::filesystem::path& file, const toml::table& t, const char* key, const std::string& field,
                                           const std::string& effect) {
    std::map<std::string, double> out;
    const toml::node* node = t.get(key);
    if (!node) return out;
    const std::string where = field + "." + key;
    const auto* table = node->as_table();
    if (!table) throw InputError(file, line_of(*node), where, "expects a table of the effect's parameters and their true values, e.g. { \"deadtime.voltage\" = 0.28 }");
    std::vector<std::string> names;
    for (const auto& spec : EffectRegistry::instance().at(effect, "effect").parameters)
        if (spec.type == ParameterType::Real) names.push_back(effect + "." + spec.name);
    for (const auto& [name, value] : *table) {
        const std::string parameter(name.str());
        if (std::find(names.begin(), names.end(), parameter) == names.end())
            throw InputError(file, line_of(value), where + "." + parameter, fmt::format("not a parameter of {}: one of {}", effect, joined(names, ", ")));
        const auto v = value.value<double>();
        if (!v || !std::isfinite(*v)) throw InputError(file, line_of(value), where + "." + parameter, "expects a finite number");
        out[parameter] = *v;
    }
    return out;
}

}  // namespace

StudySpec read_study(const std::filesystem::path& path) {
    const std::string file = path.string();
    const std::string text = read_text_file(path, "study file");
    toml::table root;
    try {
        root = toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        throw InputError(file, static_cast<long>(e.source().begin.line), "", std::string(e.description()));
    }
    static const std::set<std::string> allowed{"name", "description", "profile", "model", "seeds", "pairs", "triples", "output", "effect", "outside", "together", "design", "profile_effects", "current_loop"};
    for (auto&& [key, node] : root)
        if (!allowed.count(std::string(key.str())))
            throw InputError(file, line_of(node), std::string(key.str()),
                             "unknown key (allowed: " + fmt::format("{}", fmt::join(allowed, ", ")) + ")");
    StudySpec spec;
    spec.file = path;
    const auto directory = path.parent_path();
    auto required_string = [&](std::string_view key) {
        const toml::node* n = root.get(key);
        if (!n) throw InputError(file, 0, std::string(key), "is required");
        return string_of(file, *n, std::string(key));
    };
    spec.name = required_string("name");
    if (const auto* n = root.get("description")) spec.description = string_of(file, *n, "description");
    spec.profile = directory / required_string("profile");
    spec.profile_text = read_text_file(spec.profile, "simulation profile");
    spec.output = directory / required_string("output");
    if (const auto* n = root.get("model")) spec.model = string_of(file, *n, "model");
    try {
        parse_model_spec(spec.model);
    } catch (const InputError& e) {
        throw InputError(file, line_of(*root.get("model")), "model", e.message());
    }
    const toml::node* seeds = root.get("seeds");
    if (!seeds) throw InputError(file, 0, "seeds", "is required (a count, seeds 1..N, or a list)");
    if (seeds->is_integer()) {
        const auto count = seeds->value<std::int64_t>().value_or(0);
        if (count < 1 || count > 100000) throw InputError(file, line_of(*seeds), "seeds", fmt::format("must lie in [1, 100000] (got {})", count));
        for (std::int64_t k = 1; k <= count; ++k) spec.seeds.push_back(static_cast<std::uint64_t>(k));
    } else if (const auto* list = seeds->as_array(); list && !list->empty()) {
        for (const auto& s : *list) {
            const auto v = s.value<std::int64_t>();
            if (!s.is_integer() || !v || *v < 0) throw InputError(file, line_of(s), "seeds", "expects non-negative integers");
            spec.seeds.push_back(static_cast<std::uint64_t>(*v));
        }
    } else {
        throw InputError(file, line_of(*seeds), "seeds", "expects a count or a non-empty list of integers");
    }

    std::set<std::string> names;
    each_table(file, root, "effect", {"name", "label", "clear", "weak", "in_pairs", "clear_size", "weak_size", "pseudo_true_size"}, [&](const std::string& field, const toml::table& t) {
        StudyEffect e;
        e.line = line_of(t);
        const toml::node& name = required(file, t, "name", field);
        e.name = string_of(file, name, field + ".name");
        try {
            e.name = EffectRegistry::instance().at(e.name, "effect").name;
        } catch (const UnknownPlugin& u) {
            throw InputError(file, line_of(name), field + ".name", u.what());
        }
        e.label = e.name;
        const toml::node* label = t.get("label");
        if (label) {
            e.label = string_of(file, *label, field + ".label");
            if (e.label.empty() || e.label.find_first_of("+:/ ") != std::string::npos)
                throw InputError(file, line_of(*label), field + ".label", "expects a non-empty name without '+', ':', '/' or blanks (it names cases)");
        }
        if (!names.insert(e.label).second)
            throw InputError(file, line_of(label ? *label : name), field + (label ? ".label" : ".name"),
                             "'" + e.label + "' is listed twice (a `label` tells two entries of one effect apart)");
        e.clear = toml_text(settings_table(file, t, "clear", field));
        e.clear_as_written = as_written(text, *t.get("clear"));
        if (t.get("weak")) {
            e.weak = toml_text(settings_table(file, t, "weak", field));
            e.weak_as_written = as_written(text, *t.get("weak"));
        }
        if (const auto* in_pairs = t.get("in_pairs")) {
            if (!in_pairs->is_boolean()) throw InputError(file, line_of(*in_pairs), field + ".in_pairs", "expects true or false");
            e.in_combinations = in_pairs->value<bool>().value();
        }
        e.clear_size = stated_sizes(file, t, "clear_size", field, e.name);
        e.weak_size = stated_sizes(file, t, "weak_size", field, e.name);
        if (!e.weak_size.empty() && e.weak.empty())
            throw InputError(file, line_of(*t.get("weak_size")), field + ".weak_size", "there is no near-limit case (no `weak` settings) to state it for");
        if (const auto* fitted = t.get("pseudo_true_size")) {
            if (!fitted->is_boolean()) throw InputError(file, line_of(*fitted), field + ".pseudo_true_size", "expects true or false");
            e.pseudo_true_size = fitted->value<bool>().value();
            if (e.pseudo_true_size && (!e.clear_size.empty() || !e.weak_size.empty()))
                throw InputError(file, line_of(*fitted), field + ".pseudo_true_size",
                                 "the sizes are either stated (clear_size, weak_size) or fitted to each drive without noise, not both");
        }
        spec.effects.push_back(std::move(e));
    });
    each_table(file, root, "outside", {"name", "settings", "profile", "mechanical_order"}, [&](const std::string& field, const toml::table& t) {
        StudyOutside o;
        o.line = line_of(t);
        o.name = string_of(file, required(file, t, "name", field), field + ".name");
        o.settings = toml_text(settings_table(file, t, "settings", field));
        o.settings_as_written = as_written(text, *t.get("settings"));
        if (const auto* p = t.get("profile")) {
            o.profile = directory / string_of(file, *p, field + ".profile");
            o.profile_text = read_text_file(o.profile, "simulation profile");
        }
        if (const auto* m = t.get("mechanical_order")) {
            const auto order = m->value<std::int64_t>();
            if (!m->is_integer() || !order || *order < 1 || *order > mechanical_orders)
                throw InputError(file, line_of(*m), field + ".mechanical_order",
                                 fmt::format("expects a whole number in [1, {}] (the mechanical orders diagnose tests)", mechanical_orders));
            o.mechanical_order = static_cast<int>(*order);
        }
        spec.outside.push_back(std::move(o));
    });
    if (const auto* n = root.get("current_loop")) {
        if (!n->is_boolean()) throw InputError(file, line_of(*n), "current_loop", "expects true or false");
        spec.current_loop = n->as_boolean()->get();
    }
    if (const auto* n = root.get("profile_effects")) {
        const auto* list = n->as_array();
        if (!list) throw InputError(file, line_of(*n), "profile_effects", "expects a list of effect names, e.g. [\"saturation\"]");
        for (const auto& e : *list) {
            std::string name = string_of(file, e, "profile_effects");
            try {
                name = EffectRegistry::instance().at(name, "effect").name;
            } catch (const UnknownPlugin& u) {
                throw InputError(file, line_of(e), "profile_effects", u.what());
            }
            if (std::find(spec.profile_effects.begin(), spec.profile_effects.end(), name) != spec.profile_effects.end())
                throw InputError(file, line_of(e), "profile_effects", "'" + name + "' named twice");
            spec.profile_effects.push_back(name);
        }
        std::sort(spec.profile_effects.begin(), spec.profile_effects.end());
        for (const auto& e : spec.effects)
            if (std::binary_search(spec.profile_effects.begin(), spec.profile_effects.end(), e.name))
                throw InputError(file, e.line, "effect", "'" + e.name + "' is in profile_effects: the profile holds it in every drive already");
    }
    std::set<std::string> design_names;
    each_table(file, root, "design", {"name", "description", "settings"}, [&](const std::string& field, const toml::table& t) {
        StudyDesign d;
        d.line = line_of(t);
        const toml::node& name = required(file, t, "name", field);
        d.name = string_of(file, name, field + ".name");
        if (d.name.empty() || d.name.find_first_of("+:/ ") != std::string::npos)
            throw InputError(file, line_of(name), field + ".name", "expects a non-empty name without '+', ':', '/' or blanks (it names cases)");
        if (!design_names.insert(d.name).second) throw InputError(file, line_of(name), field + ".name", "'" + d.name + "' is listed twice");
        if (const auto* n = t.get("description")) d.description = string_of(file, *n, field + ".description");
        d.settings = toml_text(settings_table(file, t, "settings", field));
        spec.designs.push_back(std::move(d));
    });
    each_table(file, root, "together", {"effects", "settings"}, [&](const std::string& field, const toml::table& t) {
        StudyTogether g;
        g.line = line_of(t);
        const toml::node& effects = required(file, t, "effects", field);
        const auto* list = effects.as_array();
        g.effects = name_list(file, effects, field + ".effects", list ? std::max<std::size_t>(list->size(), 2) : 2, names);
        g.settings = toml_text(settings_table(file, t, "settings", field));
        spec.together.push_back(std::move(g));
    });
    if (const auto* pairs = root.get("pairs")) {
        if (pairs->is_string() && pairs->value<std::string>() == "all") {
            spec.all_pairs = true;
        } else if (const auto* list = pairs->as_array()) {
            spec.all_pairs = false;
            for (const auto& p : *list) spec.pairs.push_back(name_list(file, p, "pairs", 2, names));
        } else {
            throw InputError(file, line_of(*pairs), "pairs", "expects \"all\" or a list of [\"a\", \"b\"] pairs");
        }
    }
    if (const auto* triples = root.get("triples")) {
        const auto* list = triples->as_array();
        if (!list) throw InputError(file, line_of(*triples), "triples", "expects a list of [\"a\", \"b\", \"c\"] triples");
        for (const auto& t : *list) spec.triples.push_back(name_list(file, t, "triples", 3, names));
    }
    return spec;
}

std::vector<StudyCase> study_cases(const StudySpec& spec) {
    std::map<std::string, const StudyEffect*> by_name;  // by label
    for (const auto& e : spec.effects) by_name[e.label] = &e;
    const std::string file = spec.file.string();
    // The settings of several imperfections, merged. Two that set one key differently cannot be
    // simulated together unless a [[together]] table for a subset of them settles that key.
    auto combine = [&](const std::vector<std::pair<std::string, std::string>>& parts) {
        toml::table merged;
        std::map<std::string, std::string> conflicts;  // dotted key -> "a and b"
        std::string first;
        // A plain reference, not a structured binding: clang 14 cannot capture a binding in a lambda.
        for (const auto& part : parts) {
            const std::string& name = part.first;
            merge(merged, parse_settings(part.second, file), "", [&](const std::string& key) { conflicts.emplace(key, first + " and " + name); });
            if (first.empty()) first = name;
        }
        for (const auto& g : spec.together) {
            const bool applies = std::all_of(g.effects.begin(), g.effects.end(), [&](const std::string& e) {
                return std::any_of(parts.begin(), parts.end(), [&](const auto& p) { return p.first == e; });
            });
            if (!applies) continue;
            const auto settled = parse_settings(g.settings, file);
            merge(merged, settled, "", {});
            for (auto it = conflicts.begin(); it != conflicts.end();)
                it = settled.at_path(it->first) ? conflicts.erase(it) : std::next(it);
        }
        if (!conflicts.empty()) {
            const auto& [key, who] = *conflicts.begin();
            const std::string second = who.substr(who.rfind(' ') + 1);
            throw InputError(file, by_name.count(second) ? by_name[second]->line : 0, key,
                             fmt::format("set differently by {}: they cannot be simulated together (a [[together]] table for them can settle it)", who));
        }
        return toml_text(merged);
    };
    std::vector<StudyCase> cases;
    // Named members, not a brace list: the design and the outside cases' own fields stay at their defaults.
    auto add_case = [&](std::string label, std::string kind, std::string magnitude, std::vector<std::string> truth, std::string settings,
                        std::map<std::string, std::map<std::string, double>> sizes) -> StudyCase& {
        StudyCase c;
        c.label = std::move(label);
        c.kind = std::move(kind);
        c.magnitude = std::move(magnitude);
        c.truth = std::move(truth);
        c.settings = std::move(settings);
        c.sizes = std::move(sizes);
        return cases.emplace_back(std::move(c));
    };
    add_case("clean", "clean", "", {}, "", {});
    // An effect whose sizes each drive fits (pseudo_true_size) has none stated.
    auto add_single = [&](const StudyEffect& e, const char* magnitude, const std::string& settings, const std::map<std::string, double>& size) {
        StudyCase& c = add_case(e.label, "single", magnitude, {e.name}, combine({{e.label, settings}}), {});
        if (e.pseudo_true_size) c.pseudo_true_sized = {e.name};
        else c.sizes = {{e.name, size}};
    };
    for (const auto& e : spec.effects) add_single(e, "clear", e.clear, e.clear_size);
    for (const auto& e : spec.effects)
        if (!e.weak.empty()) add_single(e, "weak", e.weak, e.weak_size);
    std::vector<std::vector<std::string>> pairs = spec.pairs;
    if (spec.all_pairs)
        for (std::size_t a = 0; a < spec.effects.size(); ++a)
            for (std::size_t b = a + 1; b < spec.effects.size(); ++b) {
                if (!spec.effects[a].in_combinations || !spec.effects[b].in_combinations) continue;
                if (spec.effects[a].name == spec.effects[b].name) continue;  // two sizes of one effect
                std::vector<std::string> p{spec.effects[a].label, spec.effects[b].label};
                std::sort(p.begin(), p.end());
                pairs.push_back(p);
            }
    auto add_combination = [&](const std::vector<std::string>& names, const char* kind) {
        std::vector<std::pair<std::string, std::string>> parts;
        std::map<std::string, std::map<std::string, double>> sizes;
        std::vector<std::string> truth, pseudo_true_sized;
        for (const auto& n : names) {
            const StudyEffect& e = *by_name[n];
            if (std::find(truth.begin(), truth.end(), e.name) != truth.end())
                throw InputError(file, e.line, kind, fmt::format("{} names {} twice (labels {})", joined(names, "+"), e.name, joined(names, ", ")));
            parts.emplace_back(n, e.clear);
            if (e.pseudo_true_size) pseudo_true_sized.push_back(e.name);
            else sizes[e.name] = e.clear_size;
            truth.push_back(e.name);
        }
        std::sort(truth.begin(), truth.end());
        add_case(joined(names, "+"), kind, "clear", truth, combine(parts), sizes).pseudo_true_sized = std::move(pseudo_true_sized);
    };
    for (const auto& p : pairs) add_combination(p, "pair");
    for (const auto& t : spec.triples) add_combination(t, "triple");
    for (const auto& o : spec.outside) {
        StudyCase& c = add_case("outside:" + o.name, "outside", "clear", {}, combine({{o.name, o.settings}}), {});
        c.outside = true;
        c.profile = o.profile;
        c.profile_text = o.profile_text;
        c.mechanical_order = o.mechanical_order;
    }
    if (!spec.profile_effects.empty())
        for (auto& c : cases) {
            std::vector<std::string> truth;
            std::set_union(c.truth.begin(), c.truth.end(), spec.profile_effects.begin(), spec.profile_effects.end(), std::back_inserter(truth));
            c.truth = std::move(truth);
        }
    if (!spec.designs.empty()) {
        // Every case on every design, design-major.
        std::vector<StudyCase> on_designs;
        for (const auto& d : spec.designs)
            for (auto c : cases) {
                c.design = d.name;
                c.design_settings = d.settings;
                on_designs.push_back(std::move(c));
            }
        cases = std::move(on_designs);
    }
    if (!spec.only.empty()) std::erase_if(cases, [&](const StudyCase& c) { return case_name(c).find(spec.only) == std::string::npos; });
    return cases;
}

std::string case_profile(const StudySpec& spec, const StudyCase& c, std::uint64_t seed) {
    toml::table profile = c.profile.empty() ? parse_settings(spec.profile_text, spec.profile.string()) : parse_settings(c.profile_text, c.profile.string());
    if (!c.design_settings.empty()) merge(profile, parse_settings(c.design_settings, spec.file.string()), "", {});
    merge(profile, parse_settings(c.settings, spec.file.string()), "", {});
    toml::table noise;
    noise.insert("seed", static_cast<std::int64_t>(seed));
    toml::table seed_table;
    seed_table.insert("noise", noise);
    merge(profile, seed_table, "", {});
    return toml_text(profile);
}

namespace {

// How far the recommended model's flux linkage lies from the plant's at the logged currents: the rms
// of |psi_model - psi_plant| over the rows, relative to the rms of |psi_plant|. NaN when the plant's
// flux is linear (the base model's own law: nothing to compare beyond Ld, Lq and psi_f).
double flux_error_of(const DriveSimulation& sim, const Measurement& data, const ModelFit& fit) {
    const auto plant = plant_flux_model(sim);
    if (dynamic_cast<const LinearFlux*>(plant.get())) return std::nan("");
    const auto model = make_model(fit.spec, data);
    ModelState s = model->make_state();
    model->predict(fit.values.data(), s);
    double error = 0.0, size = 0.0;
    for (Eigen::Index j = 0; j < data.size(); ++j) {
        const Complex truth = plant->flux({data.i_d[j], data.i_q[j]}, sim.motor.psi_f);
        error += std::norm(Complex{s.psi_d[j], s.psi_q[j]} - truth);
        size += std::norm(truth);
    }
    return std::sqrt(error / size);
}

// The pseudo-true sizes of `effects` in `truth` (StudyRecord::pseudo_true_size): the law fitted to
// the drive without sensor noise, and what it shows on this log in the noise the diagnosis measured.
void fit_pseudo_true(const Measurement& quiet, const ModelSpec& truth, const std::vector<std::string>& effects, FitOptions options,
                     const NoiseEstimate& noise, StudyRecord& r) {
    options.intervals = false;
    options.keep_residual = false;
    const ModelFit fit = fit_model(quiet, truth, options);
    ModelSpec rest = truth;
    for (const auto& e : effects) rest = rest.without(e);
    const ModelFit without = fit_model(quiet, rest, options);
    const auto model = make_model(truth, quiet);
    const auto free = free_parameters(truth);
    int added = 0;
    const auto& laws = model->effects();
    for (std::size_t e = 0; e < laws.size(); ++e) {
        if (std::find(effects.begin(), effects.end(), laws[e]->name()) == effects.end()) continue;
        const Eigen::Index first = model->parameter_offset(e);
        const Eigen::Index end = e + 1 < laws.size() ? model->parameter_offset(e + 1) : model->parameter_count();
        for (Eigen::Index j = first; j < end; ++j) {
            added += free[static_cast<std::size_t>(j)] ? 1 : 0;
            if (laws[e]->is_size(static_cast<std::size_t>(j - first))) r.pseudo_true_size[model->parameter_names()[static_cast<std::size_t>(j)]] = fit.values[j];
        }
    }
    // As detection_limits() states a limit: the likelihood ratio in each axis's long-run noise, the
    // search's need for `added` parameters, the voltage against the noise's resolution.
    const Eigen::Array2d gained = without.axis_rss.array() - fit.axis_rss.array();
    r.pseudo_true_evidence = (gained / noise.long_run.array().square()).sum();
    r.pseudo_true_needed = added * std::log(std::max(noise.effective_samples, 2.0)) - evidence::supported_bic;
    r.pseudo_true_voltage = std::sqrt(std::max(gained.sum(), 0.0) / (2.0 * static_cast<double>(quiet.size())));
    r.pseudo_true_relevant = evidence::relevant_voltage * std::sqrt(noise.sigma.squaredNorm() / 2.0);
}

}  // namespace

StudyRun run_study(const StudySpec& spec, std::vector<StudyCase> cases, const DiagnosisOptions& options,
                   const std::function<void(std::size_t, std::size_t)>& progress) {
    StudyRun run;
    run.cases = std::move(cases);
    const ModelSpec model = parse_model_spec(spec.model);
    const std::size_t total = run.cases.size() * spec.seeds.size();
    run.records.resize(total);
    // Every case's profile is checked before any drive runs, so a bad setting stops the study at once.
    auto profile_of = [&](const StudyCase& c) { return c.profile.empty() ? spec.profile : c.profile; };
    for (const auto& c : run.cases) {
        const std::string source = fmt::format("{} (case {})", profile_of(c).string(), case_name(c));
        parse_simulation_profile(case_profile(spec, c, spec.seeds.front()), source, profile_of(c).parent_path());
    }
    std::atomic<std::size_t> done{0};
    std::mutex progress_mutex;
    // A drive that fails (its simulation refuses a setting, say) stops the study with its error. The
    // error is caught inside the task and rethrown once the loop has finished: an exception leaving a
    // task would cancel the loop's task group, and with it the parallel algorithms of the diagnoses
    // still running on other threads, which then return half-done work (a crash, not the message).
    std::atomic<bool> failed{false};
    std::mutex failure_mutex;
    std::exception_ptr failure;
    std::size_t failed_job = total;
    auto run_job = [&](std::size_t job) {
        const auto start = std::chrono::steady_clock::now();
        const std::size_t case_index = job / spec.seeds.size();
        const StudyCase& c = run.cases[case_index];
        StudyRecord r;
        r.case_index = case_index;
        r.seed = spec.seeds[job % spec.seeds.size()];
        const std::string source = fmt::format("{} (case {}, seed {})", profile_of(c).string(), case_name(c), r.seed);
        const DriveSimulation sim = parse_simulation_profile(case_profile(spec, c, r.seed), source, profile_of(c).parent_path());
        SimulationResult result;
        try {
            result = simulate(sim);
        } catch (const std::runtime_error& e) {  // e.g. a saturating plant asked for a flux no current gives
            if (dynamic_cast<const InputError*>(&e)) throw;
            throw InputError(source, 0, "", std::string("simulation failed: ") + e.what());
        }
        if (!spec.keep_data.empty()) {
            std::string name;
            for (char ch : (c.design.empty() ? "" : c.design + "_") + c.label + "_" + c.magnitude) name += std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' ? ch : '-';
            write_simulation(spec.keep_data / fmt::format("{}_seed{}.csv", name, r.seed), sim, result, source);
        }
        result.data.source = source;
        // The same drive without sensor noise (what the noise a diagnosis measures, and a law's
        // pseudo-true values, are judged against).
        // Simulated once, when first asked for.
        std::optional<Measurement> quiet;
        auto quiet_data = [&]() -> const Measurement& {
            if (!quiet) {
                DriveSimulation drive = parse_simulation_profile(case_profile(spec, c, r.seed), source, profile_of(c).parent_path());
                drive.noise = SensorNoise{};
                quiet = simulate(drive).data;
            }
            return *quiet;
        };
        std::optional<OperatingPoints> points;
        if (!result.data.has_segments()) {
            // A raw log: its operating points found as `diagnose` finds them, and the noise a
            // measurement from the data should find, from the same drive without noise.
            points = find_operating_points(result.data);
            r.windows = points->windows.size();
            std::vector<std::pair<Eigen::Index, Eigen::Index>> rows;
            for (const auto& w : points->windows) rows.emplace_back(w.first, w.rows);
            r.noise_simulated = sensor_noise_in_residual(sim.motor, result.data, quiet_data(), rows);
            result.data = select_operating_points(std::move(result.data), *points);
        }
        // Whoever logs a drive knows its pole pairs: the diagnosis tests the mechanical orders with them.
        DiagnosisOptions drive_options = options;
        drive_options.pole_pairs = sim.motor.pole_pairs;
        // And the device plant's control period and carrier: it holds each voltage over a period and
        // switches it by the carrier, as a digital drive does (the averaged plant applies its voltage
        // continuously).
        // With `current_loop`, also the loop's bandwidth, through which dead time's and flux harmonics' voltages reach the logged one.
        if (sim.device) {
            drive_options.timing = DriveTiming{sim.control.control_period, sim.device->inverter.pwm_frequency, sim.control.dc_voltage,
                                               spec.current_loop ? sim.control.current_bandwidth : 0.0};
            state_current_loop(result.data, drive_options.timing);
        }
        const Diagnosis d = diagnose(result.data, model, drive_options);
        r.recommended = d.recommended.text();
        for (const auto& e : d.recommended.effects)
            if (!model.contains(e.name)) r.found.push_back(e.name);
        std::sort(r.found.begin(), r.found.end());
        std::set_difference(r.found.begin(), r.found.end(), c.truth.begin(), c.truth.end(), std::back_inserter(r.false_positives));
        std::set_difference(c.truth.begin(), c.truth.end(), r.found.begin(), r.found.end(), std::back_inserter(r.missed));
        r.not_in_library = d.not_in_library;
        r.tie = !d.tie.empty();
        r.incomplete = d.incomplete;
        r.intervals_valid = d.recommended_intervals_valid();
        for (std::size_t j = 0; j < 4; ++j) r.interval_marked[j] = d.recommended_interval_marked(j);
        for (const auto& l : d.detection_limits)
            if (std::find(r.missed.begin(), r.missed.end(), l.effect) != r.missed.end()) r.missed_limits.push_back(l);
        if (!c.pseudo_true_sized.empty()) {
            Measurement selected = points ? select_operating_points(Measurement(quiet_data()), *points) : quiet_data();
            state_current_loop(selected, drive_options.timing);
            ModelSpec truth = model;
            for (const auto& e : c.truth)
                if (!truth.contains(e)) truth = truth.with(e);
            fit_pseudo_true(selected, truth, c.pseudo_true_sized, options.fit, d.noise, r);
        }
        for (const auto& effect : r.missed) {
            if (std::find(c.pseudo_true_sized.begin(), c.pseudo_true_sized.end(), effect) != c.pseudo_true_sized.end()) {
                if (r.pseudo_true_below()) r.below_limit.push_back(effect);
                continue;
            }
            const auto stated = c.sizes.find(effect);
            if (stated == c.sizes.end() || stated->second.empty()) continue;
            bool below = true;
            for (const auto& [parameter, size] : stated->second) {
                // clang 14 (the fuzz and sanitizer builds) cannot capture a structured binding, which C++20 allows:
                // the lambda captures a reference made from it.
                const auto limit = std::find_if(r.missed_limits.begin(), r.missed_limits.end(), [&parameter = parameter](const auto& l) { return l.parameter == parameter; });
                below = below && limit != r.missed_limits.end() && std::abs(size) < limit->limit;
            }
            if (below) r.below_limit.push_back(effect);
        }
        for (const auto& h : d.mechanical_left) r.mechanical_orders.push_back(h.order);
        const bool order_named = c.mechanical_order == 0 ||
                                 std::find(r.mechanical_orders.begin(), r.mechanical_orders.end(), c.mechanical_order) != r.mechanical_orders.end();
        r.correct = r.found == c.truth && (!c.outside || (d.not_in_library && order_named));
        // The base parameters of the recommended model against the plant's (at 20 °C).
        const ModelFit* fit = &d.recommended_fit();
        // The structure the recommended set leaves, from its step of the search (the model diagnosed is the first).
        for (const auto& step : d.path)
            if (step.fit.spec.text() == r.recommended) r.structure_left = step.structure;
        const Eigen::Vector4d truth(sim.motor.rs, sim.motor.ld, sim.motor.lq, sim.motor.psi_f);
        // Corrected for the control period's sample and hold where the diagnosis was told it.
        const bool corrected = d.sample_and_hold && d.sample_and_hold->bias.allFinite();
        const Eigen::Vector4d held = corrected ? d.sample_and_hold->bias : Eigen::Vector4d::Zero();
        if (corrected) r.sample_and_hold_bias = held.cwiseQuotient(truth);
        // And for the noise the current and the voltage share, as the diagnosis measured it.
        // Where the diagnosis states it (SharedNoise::relevant), as a user would correct for it.
        const SharedNoise* stated = d.shared_noise && d.shared_noise->relevant() ? &*d.shared_noise : nullptr;
        const Eigen::Vector4d shared = stated ? stated->bias : Eigen::Vector4d::Zero();
        if (stated) r.shared_noise_bias = shared.cwiseQuotient(truth);
        r.base_error = (fit->values.head<4>() - held - shared - truth).cwiseQuotient(truth);
        // The search compares its sets without intervals; the recommended one gets them here, polished
        // from where the search left it.
        FitOptions with_intervals = options.fit;
        with_intervals.intervals = true;
        with_intervals.keep_residual = false;
        const ModelFit interval_fit = polish_model(result.data, fit->spec, fit->values, with_intervals);
        for (int j = 0; j < 4; ++j) {
            const auto [lower, upper] = stated ? stated->corrected_interval(interval_fit, j, held[j])
                                                       : std::pair{interval_fit.lower[j] - held[j], interval_fit.upper[j] - held[j]};
            if (std::isfinite(lower) && std::isfinite(upper)) r.covered[static_cast<std::size_t>(j)] = lower <= truth[j] && truth[j] <= upper ? 1 : 0;
        }
        r.flux_error = flux_error_of(sim, result.data, *fit);
        r.rms = d.model.rms.total;
        r.rms_recommended = fit->rms.total;
        r.noise = std::sqrt(d.noise.sigma.squaredNorm() / 2.0);
        if (r.raw()) r.noise_from_data = d.noise.window.sigma;
        r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        run.records[job] = std::move(r);
        const std::size_t finished = ++done;
        if (progress) {
            std::lock_guard lock(progress_mutex);
            progress(finished, total);
        }
    };
    tbb::parallel_for(std::size_t{0}, total, [&](std::size_t job) {
        if (failed) return;  // the study stops at a failed drive; what has not started does not run
        try {
            run_job(job);
        } catch (...) {
            std::lock_guard lock(failure_mutex);
            if (job < failed_job) {  // of the drives that failed before the others stopped, the first in the study's order
                failed_job = job;
                failure = std::current_exception();
            }
            failed = true;
        }
    });
    if (failure) std::rethrow_exception(failure);
    return run;
}

std::pair<double, double> wilson_interval(std::size_t k, std::size_t n) {
    if (n == 0) return {0.0, 1.0};
    const double z = 1.959963984540054, nn = static_cast<double>(n), p = static_cast<double>(k) / nn;
    const double centre = (p + z * z / (2 * nn)) / (1 + z * z / nn);
    const double half = z * std::sqrt(p * (1 - p) / nn + z * z / (4 * nn * nn)) / (1 + z * z / nn);
    return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

namespace {

struct CaseSummary {
    std::size_t runs = 0, correct = 0, any_false_positive = 0, any_missed = 0, not_in_library = 0, ties = 0;
    std::size_t right_for_log = 0;  // correct, or every effect missed below the limit printed for it
    double false_positives = 0.0;
    Eigen::Vector4d median_error = Eigen::Vector4d::Zero();  // of |relative error|, over runs
    double median_flux_error = std::nan("");                  // over the runs that have one (StudyRecord::flux_error)
    double seconds = 0.0;
    // Over the drives whose recommended model is correct: intervals of Rs, Ld, Lq, psi_f holding the
    // true value, and intervals there were.
    std::array<std::size_t, 4> covered{}, intervals{};
    // The same over those of them whose recommended model leaves no significant structure.
    std::array<std::size_t, 4> covered_without_structure{}, intervals_without_structure{};
    // The same over the intervals the diagnosis did not mark (StudyRecord::interval_marked): those
    // that owe the truth.
    std::array<std::size_t, 4> covered_unmarked{}, intervals_unmarked{};
    // Raw logs: the noise measured from the data over the simulated, median ratio per axis, and
    // the drives in which both axes are within 20 % of it.
    std::size_t raw = 0, noise_within = 0;
    Eigen::Vector2d median_noise_ratio = Eigen::Vector2d::Constant(std::nan(""));
};

// Whether any drive of the run was a raw log: only then do the tables carry the noise columns.
bool holds_raw_logs(const StudyRun& run) {
    return std::any_of(run.records.begin(), run.records.end(), [](const StudyRecord& r) { return r.raw(); });
}

// Within 20 % on both axes: what issue 21 asks of a noise estimate.
bool noise_within_a_fifth(const StudyRecord& r) {
    return ((r.noise_from_data.array() / r.noise_simulated.array() - 1.0).abs() <= 0.2).all();
}

// "95, 100, 90, 100 % of 20": the share of intervals that hold the truth, parameter by parameter.
std::string coverage_text(const std::array<std::size_t, 4>& covered, const std::array<std::size_t, 4>& intervals) {
    std::string out;
    for (std::size_t j = 0; j < 4; ++j)
        out += (j ? ", " : "") + (intervals[j] ? fmt::format("{:.0f}", 100.0 * static_cast<double>(covered[j]) / static_cast<double>(intervals[j]))
                                               : std::string("—"));
    const std::size_t most = *std::max_element(intervals.begin(), intervals.end());
    return most ? out + fmt::format(" % of {}", most) : std::string("—");
}

// The same, each share with its own count when the counts differ ("100 % of 20, 100 % of 20, 85 % of 13, ...").
std::string coverage_counts_text(const std::array<std::size_t, 4>& covered, const std::array<std::size_t, 4>& intervals) {
    if (std::adjacent_find(intervals.begin(), intervals.end(), std::not_equal_to<>()) == intervals.end()) return coverage_text(covered, intervals);
    std::string out;
    for (std::size_t j = 0; j < 4; ++j)
        out += (j ? ", " : "") + (intervals[j] ? fmt::format("{:.0f} % of {}", 100.0 * static_cast<double>(covered[j]) / static_cast<double>(intervals[j]), intervals[j])
                                               : std::string("—"));
    return out;
}

double median(std::vector<double> v) {
    if (v.empty()) return std::nan("");
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

std::vector<CaseSummary> summaries(const StudyRun& run) {
    std::vector<CaseSummary> out(run.cases.size());
    std::vector<std::array<std::vector<double>, 4>> errors(run.cases.size());
    std::vector<std::vector<double>> flux_errors(run.cases.size());
    std::vector<std::array<std::vector<double>, 2>> noise_ratios(run.cases.size());
    for (const auto& r : run.records) {
        auto& s = out[r.case_index];
        if (std::isfinite(r.flux_error)) flux_errors[r.case_index].push_back(r.flux_error);
        if (r.raw()) {
            ++s.raw;
            s.noise_within += noise_within_a_fifth(r) ? 1 : 0;
            for (int a = 0; a < 2; ++a) noise_ratios[r.case_index][static_cast<std::size_t>(a)].push_back(r.noise_from_data[a] / r.noise_simulated[a]);
        }
        ++s.runs;
        s.correct += r.correct ? 1 : 0;
        s.right_for_log += r.right_for_this_log() ? 1 : 0;
        s.any_false_positive += r.false_positives.empty() ? 0 : 1;
        s.any_missed += r.missed.empty() ? 0 : 1;
        s.not_in_library += r.not_in_library ? 1 : 0;
        s.ties += r.tie ? 1 : 0;
        s.false_positives += static_cast<double>(r.false_positives.size());
        s.seconds += r.seconds;
        for (int j = 0; j < 4; ++j) errors[r.case_index][static_cast<std::size_t>(j)].push_back(std::abs(r.base_error[j]));
        if (r.correct)
            for (std::size_t j = 0; j < 4; ++j)
                if (r.covered[j] >= 0) {
                    ++s.intervals[j];
                    s.covered[j] += static_cast<std::size_t>(r.covered[j]);
                    if (!r.interval_marked[j]) {
                        ++s.intervals_unmarked[j];
                        s.covered_unmarked[j] += static_cast<std::size_t>(r.covered[j]);
                    }
                    if (r.structure_left > 0.0) continue;
                    ++s.intervals_without_structure[j];
                    s.covered_without_structure[j] += static_cast<std::size_t>(r.covered[j]);
                }
    }
    for (std::size_t c = 0; c < out.size(); ++c) {
        if (out[c].runs > 0) out[c].false_positives /= static_cast<double>(out[c].runs);
        for (int j = 0; j < 4; ++j) out[c].median_error[j] = median(errors[c][static_cast<std::size_t>(j)]);
        out[c].median_flux_error = median(flux_errors[c]);
        for (int a = 0; a < 2; ++a) out[c].median_noise_ratio[a] = median(noise_ratios[c][static_cast<std::size_t>(a)]);
    }
    return out;
}

std::string rate(std::size_t k, std::size_t n) {
    const auto [lo, hi] = wilson_interval(k, n);
    return fmt::format("{}/{} = {:.0f} % [{:.0f}, {:.0f}]", k, n, 100.0 * static_cast<double>(k) / static_cast<double>(std::max<std::size_t>(n, 1)),
                       100.0 * lo, 100.0 * hi);
}

}  // namespace

std::string study_markdown(const StudySpec& spec, const StudyRun& run) {
    const auto s = summaries(run);
    Document doc;
    doc.add(Heading{1, spec.name});
    doc.add(Paragraph{spec.description});
    doc.add(Paragraph{fmt::format("Profile `{}`, model diagnosed `{}`, {} noise seeds per case, {} cases, {} drives. A drive counts as correct when the "
                                  "recommended model adds exactly the effects that were simulated (and, for an effect the library lacks, nothing while "
                                  "saying \"not in the library\" and, when the study file names the mechanical order it leaves, naming that order). Rates with Wilson 95 % intervals; parameter errors: median over seeds of |fitted - "
                                  "true| / true of the recommended model's base parameters. Interval coverage: over the drives whose recommended model is "
                                  "correct, the share in which the 95 % interval of each base parameter (the recommended model polished with intervals) "
                                  "holds the plant's value; at least 90 % is what a 95 % interval owes.{}{}{} \"Where no structure is left\": the same over the drives "
                                  "whose recommended model leaves no significant structure in the residual (segment means, angle harmonics). \"Correct or "
                                  "below the printed limit\": also counting a drive that added nothing false, did not say \"not in the library\" and missed only effects whose true size, as the "
                                  "study file states it (`clear_size`, `weak_size`), lies below the detection limit the diagnosis printed for them.",
                                  spec.profile.filename().string(), spec.model, spec.seeds.size(), run.cases.size(), run.records.size(),
                                  std::any_of(run.records.begin(), run.records.end(), [](const StudyRecord& r) { return r.sample_and_hold_bias.has_value(); })
                                      ? " The device plant holds each voltage over a control period and switches it by a carrier, as a digital drive "
                                        "does, and the diagnosis is told the period, the carrier frequency and the DC voltage as it is told the pole "
                                        "pairs: errors and intervals are of the base parameters corrected for the sample and hold and the carrier's "
                                        "ripple (`diagnose --control-period --carrier-frequency --dc-voltage`, docs/diagnosis.md)."
                                      : "",
                                  spec.current_loop ? " The diagnosis is also told the drive's current-loop bandwidth (`--current-bandwidth`): its models "
                                                      "pass the voltages of dead time and flux harmonics through the loop, row by row in time (docs/diagnosis.md, section 8)."
                                      : "",
                                  std::any_of(run.records.begin(), run.records.end(), [](const StudyRecord& r) { return r.shared_noise_bias.has_value(); })
                                      ? " Where the diagnosis states it, errors and intervals are also of the base parameters corrected for the noise "
                                        "the logged current and voltage share, as it measures that in the steady windows, the intervals widened by "
                                        "the estimate's standard error (docs/diagnosis.md, section 7)."
                                      : "")});
    // Only where a case fits its sizes, so that the other studies' tables stay as they were.
    std::vector<std::string> fitted;
    for (const auto& e : spec.effects)
        if (e.pseudo_true_size) fitted.push_back(e.label);
    if (!fitted.empty())
        doc.add(Paragraph{fmt::format("The plant's law of {} is not the library's, so no setting states its size in the law's parameters "
                                      "(`pseudo_true_size`): each drive fits the law to the same drive without noise, and a miss counts as below "
                                      "the limit when that law, on this log and in the noise the diagnosis measured, gains a likelihood ratio short of "
                                      "what the search needs for its parameters, or changes the voltage by less than the relevant amount (the two "
                                      "thresholds of each printed limit; records: `pseudo_true_size`, `pseudo_true_shows`). A printed limit is for one "
                                      "term alone at its declared shape, so one term may exceed it while the whole law shows less.",
                                      joined(fitted, ", "))});
    doc.add(Heading{2, "Summary"});
    const bool designs = !spec.designs.empty();
    // With designs every row names its design first.
    auto with_design = [&](std::vector<Column> columns) {
        if (designs) columns.insert(columns.begin(), Column("design"));
        return columns;
    };
    auto design_cell = [&](std::vector<Cell> row, const std::string& design) {
        if (designs) row.insert(row.begin(), Cell(design));
        return row;
    };
    Table summary("detection per kind of case", with_design({"cases", "drives", "correct", "correct or below the printed limit", "any false positive", "any missed", "said \"not in the library\"",
                                                 "95 % intervals holding the truth when correct: Rs, Ld, Lq, psi_f",
                                                 "the same where no structure is left",
                                                 "the same of the intervals not marked (not valid, or a stated bias)"}));
    auto group_on = [&](const std::string& design, const std::string& title, const std::function<bool(const StudyCase&)>& kind_of) {
        const auto in = [&](const StudyCase& c) { return c.design == design && kind_of(c); };
        std::size_t n = 0, k = 0, fp = 0, miss = 0, nil = 0, right = 0;
        std::array<std::size_t, 4> covered{}, intervals{}, covered_clean{}, intervals_clean{}, covered_unmarked{}, intervals_unmarked{};
        for (std::size_t c = 0; c < run.cases.size(); ++c) {
            if (!in(run.cases[c])) continue;
            n += s[c].runs;
            k += s[c].correct;
            right += s[c].right_for_log;
            fp += s[c].any_false_positive;
            miss += s[c].any_missed;
            nil += s[c].not_in_library;
            for (std::size_t j = 0; j < 4; ++j) {
                covered[j] += s[c].covered[j];
                intervals[j] += s[c].intervals[j];
                covered_clean[j] += s[c].covered_without_structure[j];
                intervals_clean[j] += s[c].intervals_without_structure[j];
                covered_unmarked[j] += s[c].covered_unmarked[j];
                intervals_unmarked[j] += s[c].intervals_unmarked[j];
            }
        }
        if (n > 0)
            summary.add_row(design_cell({title, std::to_string(n), rate(k, n), rate(right, n), rate(fp, n), rate(miss, n), rate(nil, n), coverage_text(covered, intervals),
                                         coverage_text(covered_clean, intervals_clean), coverage_counts_text(covered_unmarked, intervals_unmarked)},
                                        design));
    };
    std::vector<std::string> design_names;
    for (const auto& d : spec.designs) design_names.push_back(d.name);
    if (design_names.empty()) design_names.emplace_back();
    for (const auto& design : design_names) {
        auto group = [&](const std::string& title, const std::function<bool(const StudyCase&)>& kind_of) { group_on(design, title, kind_of); };
        group(spec.profile_effects.empty() ? "clean data" : "the profile's own effects alone (" + joined(spec.profile_effects, ", ") + ")",
              [](const StudyCase& c) { return c.kind == "clean"; });
        group("single effects, clear", [](const StudyCase& c) { return c.kind == "single" && c.magnitude == "clear"; });
        group("single effects, near the limit", [](const StudyCase& c) { return c.kind == "single" && c.magnitude == "weak"; });
        group("pairs, clear", [](const StudyCase& c) { return c.kind == "pair"; });
        group("triples, clear", [](const StudyCase& c) { return c.kind == "triple"; });
        group("effects outside the library", [](const StudyCase& c) { return c.kind == "outside"; });
    }
    doc.add(std::move(summary));
    doc.add(Heading{2, "Per case"});
    // Only a study whose plants saturate has a flux error to show.
    const bool flux = std::any_of(run.records.begin(), run.records.end(), [](const StudyRecord& r) { return std::isfinite(r.flux_error); });
    std::vector<Column> per_case_columns = with_design({"case", "kind", "magnitude", "correct", "missed below the printed limit", "false positives per drive", "missed", "not in library", "ties",
                                          Column("median error Rs, Ld, Lq, psi_f", "%"), "intervals holding the truth when correct",
                                          "most common wrong answer"});
    if (flux) per_case_columns.insert(per_case_columns.end() - 1, Column("median flux error against the plant's", "%"));
    // Only a study of raw logs measures its noise against the simulated.
    const bool raw = holds_raw_logs(run);
    if (raw) {
        per_case_columns.insert(per_case_columns.end() - 1, Column("noise from the data / simulated, median u_d, u_q"));
        per_case_columns.insert(per_case_columns.end() - 1, Column("noise within 20 % on both axes"));
    }
    Table per_case("detection per case", std::move(per_case_columns));
    for (std::size_t c = 0; c < run.cases.size(); ++c) {
        std::map<std::string, int> wrong;
        for (const auto& r : run.records)
            if (r.case_index == c && !r.correct) ++wrong[r.recommended + (r.not_in_library ? " (not in library)" : "") + (r.tie ? " (tie)" : "")];
        std::string common = "—";
        int most = 0;
        for (const auto& [answer, count] : wrong)
            if (count > most) {
                most = count;
                common = fmt::format("`{}` ({}x)", answer, count);
            }
        const auto& x = s[c];
        std::vector<Cell> row = design_cell({run.cases[c].label, run.cases[c].kind, run.cases[c].magnitude.empty() ? "—" : run.cases[c].magnitude, rate(x.correct, x.runs),
                          std::to_string(x.right_for_log - x.correct), fmt::format("{:.2f}", x.false_positives), std::to_string(x.any_missed), std::to_string(x.not_in_library),
                          std::to_string(x.ties),
                          fmt::format("{:.2f}, {:.2f}, {:.2f}, {:.2f}", 100 * x.median_error[0], 100 * x.median_error[1], 100 * x.median_error[2],
                                      100 * x.median_error[3]),
                          coverage_text(x.covered, x.intervals), common}, run.cases[c].design);
        if (flux) row.insert(row.end() - 1, Cell(std::isfinite(x.median_flux_error) ? fmt::format("{:.2f}", 100 * x.median_flux_error) : "—"));
        if (raw) {
            row.insert(row.end() - 1, Cell(x.raw ? fmt::format("{:.3f}, {:.3f}", x.median_noise_ratio[0], x.median_noise_ratio[1]) : "—"));
            row.insert(row.end() - 1, Cell(x.raw ? fmt::format("{}/{}", x.noise_within, x.raw) : "—"));
        }
        per_case.add_row(std::move(row));
    }
    doc.add(std::move(per_case));
    if (designs) {
        doc.add(Heading{2, "The designs"});
        // The keys a design sets, not its values: a design may replace the whole list of segments.
        Table table("the designs", {"design", "what it is", "profile keys it sets (values in the study file)"});
        for (const auto& d : spec.designs) {
            std::vector<std::string> keys;
            const std::function<void(const toml::table&, const std::string&)> collect = [&](const toml::table& t, const std::string& prefix) {
                for (auto&& [key, node] : t) {
                    const std::string path = prefix + std::string(key.str());
                    if (const auto* inner = node.as_table())
                        collect(*inner, path + ".");
                    else if (const auto* list = node.as_array(); list && list->is_array_of_tables())
                        keys.push_back(fmt::format("{} ({})", path, list->size()));
                    else
                        keys.push_back(path);
                }
            };
            collect(parse_settings(d.settings, spec.file.string()), "");
            table.add_row({d.name, d.description.empty() ? "—" : d.description, joined(keys, ", ")});
        }
        doc.add(std::move(table));
    }
    if (spec.effects.empty() && spec.outside.empty()) return markdown(doc);
    doc.add(Heading{2, "The settings of each effect"});
    // The cells put the settings on one line (markdown_table_cell makes line breaks blanks).
    Table settings("the settings of each effect", {"effect", "clear", "near the limit"});
    for (const auto& e : spec.effects)
        settings.add_row({e.label, "`" + e.clear_as_written + "`", e.weak.empty() ? std::string("—") : "`" + e.weak_as_written + "`"});
    for (const auto& o : spec.outside)
        settings.add_row({o.name + " (not in the library)",
                          "`" + o.settings_as_written + "`" + (o.profile.empty() ? std::string() : " on `" + o.profile.filename().string() + "`"), "—"});
    doc.add(std::move(settings));
    return markdown(doc);
}

std::string study_csv(const StudyRun& run) {
    const auto s = summaries(run);
    const bool designs = std::any_of(run.cases.begin(), run.cases.end(), [](const StudyCase& c) { return !c.design.empty(); });
    std::vector<Column> columns{"case", "kind", "magnitude", "drives", "correct", "rate", "rate_low95", "rate_high95", "right_for_log", "false_positives_per_drive", "any_missed",
                 "not_in_library", "ties", "median_abs_error_rs", "median_abs_error_ld", "median_abs_error_lq", "median_abs_error_psi_f",
                 "coverage_rs", "coverage_ld", "coverage_lq", "coverage_psi_f", "coverage_drives",
                 "unmarked_coverage_rs", "unmarked_coverage_ld", "unmarked_coverage_lq", "unmarked_coverage_psi_f", "mean_seconds"};
    if (designs) columns.insert(columns.begin(), Column("design"));
    // Always there (empty where the plant's flux is linear), so that a subset of a study has the columns of the whole.
    columns.insert(columns.end() - 1, Column("median_flux_error"));
    const bool raw = holds_raw_logs(run);
    if (raw)
        for (const char* name : {"median_noise_ratio_u_d", "median_noise_ratio_u_q", "noise_within_20_percent"}) columns.insert(columns.end() - 1, Column(name));
    Table table("detection per case", std::move(columns));
    auto g6 = [](double v) { return fmt::format("{:.6g}", v); };
    for (std::size_t c = 0; c < run.cases.size(); ++c) {
        const auto& x = s[c];
        const auto [lo, hi] = wilson_interval(x.correct, x.runs);
        auto coverage = [&](std::size_t j) {
            return x.intervals[j] ? g6(static_cast<double>(x.covered[j]) / static_cast<double>(x.intervals[j])) : std::string();
        };
        auto unmarked = [&](std::size_t j) {
            return x.intervals_unmarked[j] ? g6(static_cast<double>(x.covered_unmarked[j]) / static_cast<double>(x.intervals_unmarked[j])) : std::string();
        };
        std::vector<Cell> row{run.cases[c].label, run.cases[c].kind, run.cases[c].magnitude, std::to_string(x.runs), std::to_string(x.correct),
                       g6(static_cast<double>(x.correct) / static_cast<double>(std::max<std::size_t>(x.runs, 1))), g6(lo), g6(hi),
                       std::to_string(x.right_for_log), g6(x.false_positives), std::to_string(x.any_missed), std::to_string(x.not_in_library), std::to_string(x.ties),
                       g6(x.median_error[0]), g6(x.median_error[1]), g6(x.median_error[2]), g6(x.median_error[3]),
                       coverage(0), coverage(1), coverage(2), coverage(3),
                       std::to_string(*std::max_element(x.intervals.begin(), x.intervals.end())),
                       unmarked(0), unmarked(1), unmarked(2), unmarked(3),
                       fmt::format("{:.4g}", x.seconds / static_cast<double>(std::max<std::size_t>(x.runs, 1)))};
        if (designs) row.insert(row.begin(), Cell(run.cases[c].design));
        row.insert(row.end() - 1, Cell(std::isfinite(x.median_flux_error) ? g6(x.median_flux_error) : std::string()));
        if (raw) {
            row.insert(row.end() - 1, Cell(x.raw ? g6(x.median_noise_ratio[0]) : std::string()));
            row.insert(row.end() - 1, Cell(x.raw ? g6(x.median_noise_ratio[1]) : std::string()));
            row.insert(row.end() - 1, Cell(x.raw ? std::to_string(x.noise_within) : std::string()));
        }
        table.add_row(std::move(row));
    }
    return csv(table);
}

nlohmann::ordered_json study_record_json(const StudyRun& run, const StudyRecord& r) {
    const auto& c = run.cases[r.case_index];
    auto covered = [&](std::size_t j) { return r.covered[j] < 0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(r.covered[j] == 1); };
    auto missed_limits = nlohmann::ordered_json::array();
    for (const auto& l : r.missed_limits)
        missed_limits.push_back({{"parameter", l.parameter}, {"limit", std::isfinite(l.limit) ? nlohmann::ordered_json(l.limit) : nlohmann::ordered_json(nullptr)}});
    nlohmann::ordered_json out{{"case", c.label}};
    if (!c.design.empty()) out["design"] = c.design;
    out.update(nlohmann::ordered_json{
            {"kind", c.kind},
            {"magnitude", c.magnitude},
            {"seed", r.seed},
            {"truth", c.truth},
            {"outside", c.outside},
            {"recommended_model", r.recommended},
            {"found", r.found},
            {"correct", r.correct},
            {"false_positives", r.false_positives},
            {"missed", r.missed},
            {"not_in_library", r.not_in_library},
            {"tie", r.tie},
            {"incomplete", r.incomplete},
            {"intervals_valid", r.intervals_valid},
            {"interval_marked", {{"Rs", r.interval_marked[0]}, {"Ld", r.interval_marked[1]}, {"Lq", r.interval_marked[2]}, {"psi_f", r.interval_marked[3]}}},
            {"missed_detection_limits", missed_limits},
            {"below_detection_limit", r.below_limit},
            {"base_error", {{"Rs", r.base_error[0]}, {"Ld", r.base_error[1]}, {"Lq", r.base_error[2]}, {"psi_f", r.base_error[3]}}},
            {"interval_holds_truth", {{"Rs", covered(0)}, {"Ld", covered(1)}, {"Lq", covered(2)}, {"psi_f", covered(3)}}},
            {"structure_left", r.structure_left},
            {"rms", r.rms},
            {"rms_recommended", r.rms_recommended},
            {"noise", r.noise}});
    if (r.sample_and_hold_bias)
        out["sample_and_hold_bias"] = {{"Rs", (*r.sample_and_hold_bias)[0]}, {"Ld", (*r.sample_and_hold_bias)[1]},
                                       {"Lq", (*r.sample_and_hold_bias)[2]}, {"psi_f", (*r.sample_and_hold_bias)[3]}};
    if (r.shared_noise_bias)
        out["shared_noise_bias"] = {{"Rs", (*r.shared_noise_bias)[0]}, {"Ld", (*r.shared_noise_bias)[1]},
                                    {"Lq", (*r.shared_noise_bias)[2]}, {"psi_f", (*r.shared_noise_bias)[3]}};
    // Only when some were named, so that the records of drives without a whole turn stay as they were.
    if (!r.mechanical_orders.empty()) out["mechanical_orders"] = r.mechanical_orders;
    // Only for the cases that fit them (StudyCase::pseudo_true_sized).
    if (!r.pseudo_true_size.empty()) {
        out["pseudo_true_size"] = r.pseudo_true_size;
        out["pseudo_true_shows"] = {{"likelihood_ratio", r.pseudo_true_evidence}, {"needed", r.pseudo_true_needed},
                                    {"voltage", r.pseudo_true_voltage}, {"relevant_voltage", r.pseudo_true_relevant}};
    }
    // Only where the plant's flux is not linear (StudyRecord::flux_error).
    if (std::isfinite(r.flux_error)) out["flux_error"] = r.flux_error;
    // Only for a raw log (StudyRecord::windows).
    if (r.raw()) {
        out["steady_windows_found"] = r.windows;
        out["noise_from_data"] = {{"u_d", r.noise_from_data[0]}, {"u_q", r.noise_from_data[1]}};
        out["noise_simulated"] = {{"u_d", r.noise_simulated[0]}, {"u_q", r.noise_simulated[1]}};
    }
    out["seconds"] = r.seconds;
    return out;
}

}  // namespace mhb::pmsm
