#pragma once
// One self-contained HTML page for people: the tables sort by a click on a header, the plots are
// inline SVG, and nothing is fetched from anywhere (no network, no external script, style, font or
// image), so the page shows the same thing offline, mailed or archived.
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/report_document.hpp"

namespace mhb {

class HtmlReport {
public:
    explicit HtmlReport(std::string title = {});

    // Shown under the title as a list of labelled lines: versions, dates, machines, inputs.
    void add_provenance(std::string label, std::string value);

    // Text arguments are plain text, escaped on output; `code` and **bold** (the only inline markup the
    // Markdown reports use) become <code> and <strong>.
    void add_heading(int level, const std::string& text);  // 2 to 4; level 2 headings are listed in the contents
    void add_paragraph(const std::string& text);
    void add_list(const std::vector<std::string>& items);
    void add_preformatted(const std::string& text);
    // Cells that start with a number (e.g. "1.5e-05", "10 (2 failed)", "0.50 (large)") are right-aligned
    // and carry it in data-sort; "", "–", "—" and "-" mark a missing value, which sorts last. A column
    // whose cells all carry data-sort sorts numerically, any other column as text.
    // Notes follow the table as paragraphs.
    void add_table(const Table& table);
    // Inlines the SVG file as a figure scaled to the page's width (up to a quarter wider than drawn);
    // InputError when it cannot be read or is not an SVG image.
    void add_plot(const std::filesystem::path& svg, const std::string& caption);
    // A collapsed block of preformatted text, e.g. the configuration an experiment ran from.
    void add_details(const std::string& summary, const std::string& text);

    // Adds each block of the document: the first level-1 heading becomes the page's title when it has
    // none, and an image is drawn from the SVG beside its PNG in `image_directory`.
    void add_document(const Document& document, const std::filesystem::path& image_directory);

    std::size_t table_count() const { return tables_; }
    std::size_t plot_count() const { return plots_; }

    std::string html() const;
    // Writes html() to `file` (temporary file and rename); InputError naming the file when it cannot.
    void write(const std::filesystem::path& file) const;

private:
    std::string title_;
    std::vector<std::pair<std::string, std::string>> provenance_;
    std::vector<std::pair<std::string, std::string>> contents_;  // level 2 headings: id, text
    std::string body_;
    std::size_t tables_ = 0, plots_ = 0, headings_ = 0;
};

// Text for HTML element content and quoted attribute values: & < > " ' escaped.
std::string html_escape(std::string_view text);

// An SVG document made ready to sit inside a page: the XML prolog, DOCTYPE and comments before the
// <svg> element dropped; the root's width and height replaced by a viewBox (kept when present) and a
// style that scales it to its container, up to 1.25 times its drawn width; every id prefixed with `id_prefix` (and the references to
// them), so that two plots' definitions cannot collide. InputError naming `source` when the text holds
// no <svg> element or holds a script.
std::string inline_svg(std::string_view svg, const std::string& id_prefix, const std::string& source);

}  // namespace mhb
