#include "framework/html_report.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <variant>

#include <fmt/format.h>

#include "framework/file_output.hpp"
#include "framework/input_error.hpp"

namespace mhb {
namespace fs = std::filesystem;

namespace {

// The page's whole style: readable at a laptop's width (a centred column up to 1200 px), wide
// tables scroll inside their own box instead of widening the page, plots shrink to the column.
constexpr std::string_view page_style = R"css(
:root { color-scheme: light; }
body { margin: 0; background: #fff; color: #1f2328; font: 15px/1.5 system-ui, -apple-system, "Segoe UI", "DejaVu Sans", sans-serif; }
main { max-width: 1200px; margin: 0 auto; padding: 1.5rem 2rem 3rem; }
h1 { font-size: 1.75rem; margin: 0 0 .75rem; overflow-wrap: anywhere; }
h2 { font-size: 1.35rem; margin: 2.25rem 0 .6rem; padding-bottom: .25rem; border-bottom: 1px solid #d8dee4; overflow-wrap: anywhere; }
h3 { font-size: 1.1rem; margin: 1.6rem 0 .5rem; overflow-wrap: anywhere; }
h4 { font-size: 1rem; margin: 1.2rem 0 .4rem; }
p, li { max-width: 75rem; overflow-wrap: anywhere; }
code { font-family: "DejaVu Sans Mono", ui-monospace, monospace; font-size: .88em; background: #f3f4f6; padding: .05em .3em; border-radius: 3px; }
pre { font-family: "DejaVu Sans Mono", ui-monospace, monospace; font-size: .85rem; line-height: 1.4; background: #f6f8fa; border: 1px solid #e1e4e8; border-radius: 6px; padding: .75rem 1rem; overflow-x: auto; }
dl.provenance { display: grid; grid-template-columns: max-content 1fr; gap: .2rem 1.2rem; margin: 0 0 1.2rem; padding: .7rem 1rem; background: #f6f8fa; border: 1px solid #e1e4e8; border-radius: 6px; font-size: .9rem; }
dl.provenance dt { font-weight: 600; color: #57606a; }
dl.provenance dd { margin: 0; overflow-wrap: anywhere; }
nav.contents { font-size: .9rem; margin: 0 0 1rem; }
nav.contents ol { display: flex; flex-wrap: wrap; gap: .2rem 1.2rem; list-style: none; margin: .3rem 0 0; padding: 0; }
nav.contents a { color: #0969da; text-decoration: none; }
nav.contents a:hover { text-decoration: underline; }
.table-box { width: fit-content; max-width: 100%; overflow-x: auto; margin: .6rem 0 1.2rem; border: 1px solid #d8dee4; border-radius: 6px; }
table { border-collapse: collapse; font-size: .875rem; }
th, td { padding: .32rem .65rem; border-bottom: 1px solid #e8ebef; text-align: left; vertical-align: top; }
th { background: #f0f3f6; font-weight: 600; }
td:first-child { white-space: nowrap; }
tbody tr:nth-child(even) { background: #fafbfc; }
tbody tr:hover { background: #eef6ff; }
td.number { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
table.sortable th { cursor: pointer; user-select: none; }
table.sortable th::after { content: "\00A0\2195"; color: #afb8c1; }
table.sortable th[aria-sort=ascending]::after { content: "\00A0\25B2"; color: #1f2328; }
table.sortable th[aria-sort=descending]::after { content: "\00A0\25BC"; color: #1f2328; }
figure.plot { margin: 1rem 0 1.8rem; }
figure.plot svg { display: block; width: 100%; height: auto; background: #fff; border: 1px solid #e1e4e8; border-radius: 4px; }
figure.plot figcaption { font-size: .85rem; color: #57606a; margin-top: .35rem; }
details { margin: .8rem 0; }
details summary { cursor: pointer; font-weight: 600; }
)css";

// Sorting: a click on a header sorts by that column, a second click reverses. Numbers compare by
// their data-sort value; missing values (data-sort="") stay last either way; ties keep their order.
// The script marks each table it can sort, so a page shown without scripts shows no sort arrows.
constexpr std::string_view sort_script = R"js(
(function () {
  function sortBy(table, th, column) {
    var body = table.tBodies[0];
    var rows = Array.prototype.slice.call(body.rows);
    var numeric = rows.every(function (r) { return r.cells[column] && r.cells[column].hasAttribute('data-sort'); });
    var ascending = th.getAttribute('aria-sort') !== 'ascending';
    Array.prototype.forEach.call(th.parentNode.cells, function (h) { h.removeAttribute('aria-sort'); });
    th.setAttribute('aria-sort', ascending ? 'ascending' : 'descending');
    var keyed = rows.map(function (r, index) {
      var cell = r.cells[column];
      var text = cell ? cell.textContent.trim() : '';
      var key = numeric ? cell.getAttribute('data-sort') : text;
      return { row: r, index: index, missing: key === '', key: numeric && key !== '' ? parseFloat(key) : key };
    });
    keyed.sort(function (a, b) {
      if (a.missing !== b.missing) return a.missing ? 1 : -1;
      var order = numeric ? (a.key < b.key ? -1 : a.key > b.key ? 1 : 0) : a.key.localeCompare(b.key, undefined, { numeric: true });
      return (ascending ? order : -order) || a.index - b.index;
    });
    keyed.forEach(function (k) { body.appendChild(k.row); });
  }
  Array.prototype.forEach.call(document.querySelectorAll('table'), function (table) {
    if (!table.tHead || !table.tBodies.length) return;
    table.classList.add('sortable');
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, column) {
      th.tabIndex = 0;
      th.title = 'Sort by this column (again: reverse)';
      th.addEventListener('click', function () { sortBy(table, th, column); });
      th.addEventListener('keydown', function (e) {
        if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); sortBy(table, th, column); }
      });
    });
  });
})();
)js";

std::string_view trim(std::string_view s) {
    const auto first = s.find_first_not_of(" \t\r");
    if (first == std::string_view::npos) return {};
    return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

// Text with the reports' inline Markdown: `code` and **bold**; a marker without its closing twin is text.
std::string inline_html(std::string_view text) {
    std::string out;
    for (std::size_t i = 0; i < text.size();) {
        if (text[i] == '`') {
            const auto close = text.find('`', i + 1);
            if (close != std::string_view::npos) {
                out += "<code>" + html_escape(text.substr(i + 1, close - i - 1)) + "</code>";
                i = close + 1;
                continue;
            }
        } else if (text.substr(i, 2) == "**") {
            const auto close = text.find("**", i + 2);
            if (close != std::string_view::npos && close > i + 2) {
                out += "<strong>" + inline_html(text.substr(i + 2, close - i - 2)) + "</strong>";
                i = close + 2;
                continue;
            }
        }
        out += html_escape(text.substr(i, 1));
        ++i;
    }
    return out;
}

bool missing_value(std::string_view cell) { return cell.empty() || cell == "-" || cell == "–" || cell == "—"; }

// The number a cell starts with, when what follows it does not make the cell a word ("2opt").
std::optional<double> leading_number(std::string_view cell) {
    double value = 0;
    const char* end = cell.data() + cell.size();
    const auto [next, error] = std::from_chars(cell.data(), end, value);
    if (error != std::errc() || std::isnan(value)) return std::nullopt;
    if (next != end && *next != ' ' && *next != ',' && *next != '%') return std::nullopt;
    return value;
}

// What JavaScript's parseFloat reads back as the same number: the shortest exact form, and its names
// for the infinities.
std::string sort_key(double v) {
    if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
    return fmt::format("{}", v);
}

// One attribute of a start tag, as written.
struct Attribute {
    std::string name, value;
};

// The attributes of the start tag that begins at `tag` ("<svg ..."); `end` is set past its '>'.
std::vector<Attribute> start_tag_attributes(std::string_view text, std::size_t tag, std::size_t& end, const std::string& source) {
    std::vector<Attribute> attributes;
    std::size_t i = text.find_first_of(" \t\r\n>", tag);
    while (i < text.size()) {
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        if (i < text.size() && text[i] == '>') {
            end = i + 1;
            return attributes;
        }
        if (text.substr(i, 2) == "/>") throw InputError(source, 0, "", "the <svg> element is empty");
        const std::size_t name_start = i;
        while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i])) && text[i] != '=' && text[i] != '>') ++i;
        Attribute a{std::string(text.substr(name_start, i - name_start)), {}};
        if (i < text.size() && text[i] == '=') {
            ++i;
            if (i < text.size() && (text[i] == '"' || text[i] == '\'')) {
                const auto close = text.find(text[i], i + 1);
                if (close == std::string_view::npos) break;
                a.value = std::string(text.substr(i + 1, close - i - 1));
                i = close + 1;
            } else {
                const std::size_t value_start = i;
                while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i])) && text[i] != '>') ++i;
                a.value = std::string(text.substr(value_start, i - value_start));
            }
        }
        attributes.push_back(std::move(a));
    }
    throw InputError(source, 0, "", "the <svg> start tag is not closed");
}

std::optional<double> length_in_pixels(const std::string& value) {
    std::string_view v = trim(value);
    if (v.size() > 2 && v.substr(v.size() - 2) == "px") v.remove_suffix(2);
    double x = 0;
    const auto [next, error] = std::from_chars(v.data(), v.data() + v.size(), x);
    if (error != std::errc() || next != v.data() + v.size() || !(x > 0) || !std::isfinite(x)) return std::nullopt;
    return x;
}

bool id_character(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == ':'; }

// Each id="X" becomes id="PX", and each reference to X ('#X' in an attribute, url(#X)) becomes #PX.
// Only ids the element defines are rewritten, so colours such as '#1b9e77' are left alone.
std::string prefix_ids(std::string_view svg, const std::string& prefix) {
    auto id_value_at = [&](std::size_t i) -> std::optional<std::size_t> {
        if (svg.substr(i, 3) != "id=" || i == 0 || !std::isspace(static_cast<unsigned char>(svg[i - 1])) || i + 3 >= svg.size()) return std::nullopt;
        if (svg[i + 3] != '"' && svg[i + 3] != '\'') return std::nullopt;
        return i + 4;
    };
    std::set<std::string, std::less<>> ids;
    for (std::size_t i = 0; i < svg.size(); ++i)
        if (const auto start = id_value_at(i)) {
            const auto close = svg.find(svg[*start - 1], *start);
            if (close != std::string_view::npos) ids.emplace(svg.substr(*start, close - *start));
        }
    std::string out;
    out.reserve(svg.size() + 64 * ids.size());
    for (std::size_t i = 0; i < svg.size();) {
        if (const auto start = id_value_at(i)) {
            out.append(svg.substr(i, *start - i));
            out += prefix;
            i = *start;
            continue;
        }
        if (svg[i] == '#' && i > 0 && (svg[i - 1] == '"' || svg[i - 1] == '\'' || svg[i - 1] == '(')) {
            std::size_t j = i + 1;
            while (j < svg.size() && id_character(svg[j])) ++j;
            if (ids.count(svg.substr(i + 1, j - i - 1))) {
                out += '#' + prefix;
                out.append(svg.substr(i + 1, j - i - 1));
                i = j;
                continue;
            }
        }
        out += svg[i++];
    }
    return out;
}

std::string lowercase(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

}  // namespace

std::string html_escape(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            case '\'': out += "&#39;"; break;
            default: out += c;
        }
    }
    return out;
}

std::string inline_svg(std::string_view svg, const std::string& id_prefix, const std::string& source) {
    std::size_t start = svg.find("<svg");
    while (start != std::string_view::npos && start + 4 < svg.size() && !std::isspace(static_cast<unsigned char>(svg[start + 4])) &&
           svg[start + 4] != '>')
        start = svg.find("<svg", start + 4);
    const std::size_t close = svg.rfind("</svg>");
    if (start == std::string_view::npos || close == std::string_view::npos || close < start)
        throw InputError(source, 0, "", "not an SVG image: no <svg> element");
    const std::string_view element = svg.substr(start, close + 6 - start);
    if (lowercase(element).find("<script") != std::string::npos)
        throw InputError(source, 0, "", "the SVG image holds a script; a report inlines drawings only");

    std::size_t body = 0;
    auto attributes = start_tag_attributes(element, 0, body, source);
    std::optional<double> width, height;
    std::string view_box;
    std::string tag = "<svg";
    for (const auto& a : attributes) {
        if (a.name == "width") width = length_in_pixels(a.value);
        else if (a.name == "height") height = length_in_pixels(a.value);
        else if (a.name == "viewBox") view_box = a.value;
        else if (a.name != "style") tag += " " + a.name + "=\"" + html_escape(a.value) + "\"";
    }
    if (view_box.empty()) {
        if (!width || !height)
            throw InputError(source, 0, "", "the SVG image has neither a viewBox nor a width and height in pixels, so it cannot be scaled");
        view_box = fmt::format("0 0 {:g} {:g}", *width, *height);
    }
    // A plot shrinks to a narrow page, and grows by at most a quarter to fill the column: gnuplot's
    // 10 px text then reads about like the page's, while a small plot does not fill the screen.
    std::istringstream numbers(view_box);
    double x = 0, y = 0, w = 0, h = 0;
    numbers >> x >> y >> w >> h;
    if (!numbers || !(w > 0) || !(h > 0)) throw InputError(source, 0, "", "the SVG image's viewBox \"" + view_box + "\" is not four numbers with a positive size");
    tag += fmt::format(" viewBox=\"{}\" preserveAspectRatio=\"xMidYMid meet\" role=\"img\" style=\"max-width: {:g}px\">", html_escape(view_box), 1.25 * w);
    return prefix_ids(tag + std::string(element.substr(body)), id_prefix);
}

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

void HtmlReport::add_provenance(std::string label, std::string value) { provenance_.emplace_back(std::move(label), std::move(value)); }

void HtmlReport::add_heading(int level, const std::string& text) {
    level = std::clamp(level, 2, 4);
    const std::string id = fmt::format("section-{}", ++headings_);
    if (level == 2) contents_.emplace_back(id, text);
    body_ += fmt::format("<h{0} id=\"{1}\">{2}</h{0}>\n", level, id, inline_html(text));
}

void HtmlReport::add_paragraph(const std::string& text) { body_ += "<p>" + inline_html(text) + "</p>\n"; }

void HtmlReport::add_list(const std::vector<std::string>& items) {
    body_ += "<ul>\n";
    for (const auto& item : items) body_ += "<li>" + inline_html(item) + "</li>\n";
    body_ += "</ul>\n";
}

void HtmlReport::add_preformatted(const std::string& text) { body_ += "<pre>" + html_escape(text) + "</pre>\n"; }

void HtmlReport::add_table(const Table& table) {
    ++tables_;
    body_ += "<div class=\"table-box\"><table>\n<thead><tr>";
    for (const auto& column : table.columns()) body_ += "<th scope=\"col\">" + inline_html(column.label()) + "</th>";
    body_ += "</tr></thead>\n<tbody>\n";
    for (const auto& row : table.rows()) {
        body_ += "<tr>";
        for (const auto& c : row) {
            const std::string_view cell = trim(c.text);
            if (missing_value(cell)) body_ += "<td class=\"number\" data-sort=\"\">" + html_escape(cell) + "</td>";
            else if (const auto number = leading_number(cell))
                body_ += "<td class=\"number\" data-sort=\"" + sort_key(*number) + "\">" + inline_html(cell) + "</td>";
            else body_ += "<td>" + inline_html(cell) + "</td>";
        }
        body_ += "</tr>\n";
    }
    body_ += "</tbody>\n</table></div>\n";
    for (const auto& note : table.notes()) add_paragraph(note);
}

void HtmlReport::add_plot(const fs::path& svg, const std::string& caption) {
    std::ifstream in(svg, std::ios::binary);
    if (!in) throw InputError(svg.string(), 0, "", "cannot read the plot for the HTML report");
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    ++plots_;
    body_ += "<figure class=\"plot\">\n" + inline_svg(text, fmt::format("plot{}-", plots_), svg.string()) + "\n<figcaption>" +
             html_escape(caption) + "</figcaption>\n</figure>\n";
}

void HtmlReport::add_details(const std::string& summary, const std::string& text) {
    body_ += "<details>\n<summary>" + inline_html(summary) + "</summary>\n<pre>" + html_escape(text) + "</pre>\n</details>\n";
}

void HtmlReport::add_document(const Document& document, const fs::path& image_directory) {
    struct Add {
        HtmlReport& page;
        const fs::path& images;
        void operator()(const Heading& h) const {
            if (h.level == 1 && page.title_.empty()) page.title_ = h.text;
            else page.add_heading(h.level, h.text);
        }
        // A paragraph's lines read as one line, as they do in Markdown.
        void operator()(const Paragraph& p) const {
            std::string text;
            for (std::size_t start = 0; start <= p.text.size();) {
                auto end = p.text.find('\n', start);
                if (end == std::string::npos) end = p.text.size();
                const auto line = trim(std::string_view(p.text).substr(start, end - start));
                if (!line.empty()) text += (text.empty() ? "" : " ") + std::string(line);
                start = end + 1;
            }
            if (!text.empty()) page.add_paragraph(text);
        }
        void operator()(const Table& t) const { page.add_table(t); }
        void operator()(const Image& i) const { page.add_plot((images / i.file).replace_extension(".svg"), i.caption); }
        // Markdown shows an empty list as a blank line; a page, as nothing.
        void operator()(const BulletList& l) const {
            if (!l.items.empty()) page.add_list(l.items);
        }
        void operator()(const Preformatted& p) const { page.add_preformatted(p.text); }
    };
    for (const auto& block : document.blocks()) std::visit(Add{*this, image_directory}, block);
}

std::string HtmlReport::html() const {
    const std::string title = title_.empty() ? std::string("mhbench report") : title_;
    std::string page = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                       "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                       "<meta name=\"generator\" content=\"mhbench\">\n";
    page += "<title>" + html_escape(title) + "</title>\n<style>" + std::string(page_style) + "</style>\n</head>\n<body>\n<main>\n";
    page += "<header>\n<h1>" + inline_html(title) + "</h1>\n";
    if (!provenance_.empty()) {
        page += "<dl class=\"provenance\">\n";
        for (const auto& [label, value] : provenance_) page += "<dt>" + html_escape(label) + "</dt><dd>" + html_escape(value) + "</dd>\n";
        page += "</dl>\n";
    }
    if (contents_.size() >= 2) {
        page += "<nav class=\"contents\" aria-label=\"Contents\"><strong>Contents</strong>\n<ol>\n";
        for (const auto& [id, text] : contents_) page += "<li><a href=\"#" + id + "\">" + inline_html(text) + "</a></li>\n";
        page += "</ol>\n</nav>\n";
    }
    page += "</header>\n" + body_ + "</main>\n<script>" + std::string(sort_script) + "</script>\n</body>\n</html>\n";
    return page;
}

void HtmlReport::write(const fs::path& file) const { replace_file(file, html()); }

}  // namespace mhb
