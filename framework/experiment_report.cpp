#include "framework/experiment_report.hpp"

#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "framework/html_report.hpp"
#include "framework/provenance.hpp"

namespace mhb {
namespace fs = std::filesystem;
namespace {

std::optional<std::string> file_text(const fs::path& path) {
    std::error_code ec;
    if (path.empty() || !fs::is_regular_file(path, ec)) return std::nullopt;
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

void add_provenance(HtmlReport& page, const fs::path& directory, const ExperimentInfo& info) {
    if (info.runs.empty()) {
        page.add_provenance("trials run", "by an mhbench that did not record its version, machine or date");
    } else if (info.runs.size() == 1) {
        for (const auto& [label, value] : provenance_lines(info.runs.front())) page.add_provenance(label, value);
    } else {
        for (std::size_t k = 0; k < info.runs.size(); ++k)
            page.add_provenance(fmt::format("run {} of {}", k + 1, info.runs.size()), provenance_summary(info.runs[k]));
    }
    page.add_provenance("config", info.config_file.empty() ? std::string("not recorded") : info.config_file);
    page.add_provenance("results", directory.string());
    const Provenance now = current_provenance(0);
    page.add_provenance("report written", fmt::format("{} by mhbench {} at commit {}", now.date, now.version, now.commit));
}

// The config the run read when experiment.json holds it; else the file it names as it is now (it may
// have changed since); else experiment.json itself, which holds the resolved experiment.
void add_configuration(HtmlReport& page, const fs::path& directory, const ExperimentInfo& info) {
    page.add_heading(2, "Configuration");
    const std::string name = fs::path(info.config_file).filename().string();
    if (!info.config_text.empty()) {
        page.add_details(fmt::format("`{}` as the run read it", name), info.config_text);
    } else if (const auto now = file_text(info.config_file)) {
        page.add_details(fmt::format("`{}` as it is now: the run did not record the text it read, which may have differed", info.config_file), *now);
    } else if (const auto resolved = file_text(directory / "experiment.json")) {
        page.add_details("`experiment.json`: the resolved experiment (the run did not record its config file's text)", *resolved);
    } else {
        page.add_paragraph("Neither the config's text nor experiment.json could be read.");
    }
}

}  // namespace

fs::path write_experiment_report(const fs::path& directory, const ExperimentInfo& info, const Document& tables,
                                 const ExperimentPlots& plots) {
    HtmlReport page;
    add_provenance(page, directory, info);
    page.add_document(tables, directory);
    page.add_heading(2, "Plots");
    if (plots.images.empty()) page.add_paragraph(plots.absent_because);
    for (const auto& png : plots.images) {
        fs::path svg = png;
        page.add_plot(svg.replace_extension(".svg"), png.filename().string() + " (and .svg; its data and gnuplot script are in plot-data/)");
    }
    add_configuration(page, directory, info);
    const fs::path file = directory / "report.html";
    page.write(file);
    return file;
}

}  // namespace mhb
