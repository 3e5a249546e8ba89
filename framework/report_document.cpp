#include "framework/report_document.hpp"

#include <stdexcept>

#include <fmt/format.h>

namespace mhb {
namespace {

// One row of a pipe table. A blank slot is "| |" and an empty text "|  |": the tables have always
// told the two apart, and table.md stays byte for byte what it was.
std::string markdown_row(const std::vector<Cell>& cells) {
    std::string row = "|";
    for (const auto& cell : cells) row += cell.blank ? std::string(" |") : " " + markdown_table_cell(cell.text) + " |";
    return row + "\n";
}

std::string csv_field(const std::string& text) {
    if (text.find_first_of(",\"\n") == std::string::npos) return text;
    std::string quoted = "\"";
    for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    return quoted + "\"";
}

std::string csv_row(const std::vector<std::string>& fields) {
    std::string row;
    for (std::size_t i = 0; i < fields.size(); ++i) row += (i ? "," : "") + csv_field(fields[i]);
    return row + "\n";
}

// A header is a row whose unlabelled columns are blank slots.
std::vector<Cell> header_cells(const std::vector<Column>& columns) {
    std::vector<Cell> cells;
    for (const auto& column : columns) cells.push_back(column.label().empty() ? Cell::none() : Cell(column.label()));
    return cells;
}

struct MarkdownBlock {
    std::string operator()(const Heading& h) const { return std::string(static_cast<std::size_t>(h.level), '#') + " " + h.text + "\n"; }
    std::string operator()(const Paragraph& p) const { return p.text + "\n"; }
    std::string operator()(const Table& t) const { return markdown(t); }
    std::string operator()(const Image& i) const { return fmt::format("![{}]({})\n", i.caption, i.file); }
    std::string operator()(const BulletList& l) const {
        std::string out;
        for (const auto& item : l.items) out += "- " + item + "\n";
        return out;
    }
    std::string operator()(const Preformatted& p) const {
        std::string out;
        for (std::size_t start = 0; start <= p.text.size();) {
            auto end = p.text.find('\n', start);
            if (end == std::string::npos) end = p.text.size();
            out += "    " + p.text.substr(start, end - start) + "\n";
            start = end + 1;
        }
        return out;
    }
};

}  // namespace

std::string Column::label() const { return unit.empty() ? name : name + " (" + unit + ")"; }

Cell Cell::none() {
    Cell cell("");
    cell.blank = true;
    return cell;
}

Table::Table(std::string title, std::vector<Column> columns) : title_(std::move(title)), columns_(std::move(columns)) {}

void Table::add_row(std::vector<Cell> cells) {
    if (cells.size() != columns_.size())
        throw std::invalid_argument(fmt::format("table \"{}\": a row of {} cells for {} columns", title_, cells.size(), columns_.size()));
    rows_.push_back(std::move(cells));
}

std::string markdown_table_cell(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (char c : text) {
        if (c == '|') out += "\\|";
        else out += c == '\n' || c == '\r' ? ' ' : c;
    }
    return out;
}

std::string markdown(const Table& table) {
    std::string out = markdown_row(header_cells(table.columns())) + "|";
    for (std::size_t c = 0; c < table.columns().size(); ++c) out += "---|";
    out += "\n";
    for (const auto& row : table.rows()) out += markdown_row(row);
    for (const auto& note : table.notes()) out += "\n" + note + "\n";
    return out;
}

std::string markdown(const Document& document) {
    std::string out;
    for (std::size_t i = 0; i < document.blocks().size(); ++i) out += (i ? "\n" : "") + std::visit(MarkdownBlock{}, document.blocks()[i]);
    return out;
}

std::string csv(const Table& table) {
    std::vector<std::string> fields;
    for (const auto& column : table.columns()) fields.push_back(column.label());
    std::string out = csv_row(fields);
    for (const auto& row : table.rows()) {
        fields.clear();
        for (const auto& cell : row) fields.push_back(cell.text);
        out += csv_row(fields);
    }
    return out;
}

}  // namespace mhb
