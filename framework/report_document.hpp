#pragma once
// What a report says, apart from how it is written down: a document of blocks (headings, paragraphs,
// tables, images, lists, preformatted text) and tables with named columns. The Markdown and CSV
// writers here and HtmlReport::add_document each render the same content, so no writer has to read
// back another's output.
//
// Text in headings, paragraphs, list items and table cells may hold the only inline markup the
// reports use, `code` and **bold**: Markdown shows it as written, the HTML page as <code> and <strong>.
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace mhb {

struct Column {
    Column(std::string name, std::string unit = {}) : name(std::move(name)), unit(std::move(unit)) {}
    Column(const char* name) : name(name) {}
    std::string name;
    std::string unit;  // empty: none
    // "name (unit)", or the name alone when it has no unit.
    std::string label() const;
};

struct Cell {
    Cell(std::string text) : text(std::move(text)) {}
    Cell(const char* text) : text(text) {}
    // A slot that holds nothing by design, e.g. the spread of a value that is not a mean. Markdown
    // writes it as "| |" where an empty text cell is "|  |"; both are a missing value elsewhere.
    static Cell none();

    std::string text;  // exactly as shown
    bool blank = false;
};

class Table {
public:
    // `title` says what the table holds and names it in errors; the writers do not print it (a
    // document puts a heading before a table that needs one).
    Table(std::string title, std::vector<Column> columns);

    // std::invalid_argument when the row's cell count differs from the columns': a row that is one
    // short would shift every cell after the gap under the wrong header in CSV.
    void add_row(std::vector<Cell> cells);
    // A sentence that qualifies the table, shown after it.
    void add_note(std::string note) { notes_.push_back(std::move(note)); }

    const std::string& title() const { return title_; }
    const std::vector<Column>& columns() const { return columns_; }
    const std::vector<std::vector<Cell>>& rows() const { return rows_; }
    const std::vector<std::string>& notes() const { return notes_; }

private:
    std::string title_;
    std::vector<Column> columns_;
    std::vector<std::vector<Cell>> rows_;
    std::vector<std::string> notes_;
};

struct Heading {
    int level;  // 1 for the document's title
    std::string text;
};
struct Paragraph {
    std::string text;  // lines of it are joined by a blank in HTML
};
struct Image {
    std::string file;  // a PNG beside the document; the HTML page inlines the SVG of the same name
    std::string caption;
};
struct BulletList {
    std::vector<std::string> items;
};
struct Preformatted {
    std::string text;  // shown as is, line by line (e.g. commands to run)
};

using Block = std::variant<Heading, Paragraph, Table, Image, BulletList, Preformatted>;

class Document {
public:
    void add(Block block) { blocks_.push_back(std::move(block)); }
    void append(const Document& other) { blocks_.insert(blocks_.end(), other.blocks_.begin(), other.blocks_.end()); }
    const std::vector<Block>& blocks() const { return blocks_; }

private:
    std::vector<Block> blocks_;
};

// Blocks separated by a blank line; tables as pipe tables with each note after it as a paragraph.
std::string markdown(const Document& document);
std::string markdown(const Table& table);

// The header (column labels) and the rows; a cell holding a comma, quote or line break is quoted with
// its quotes doubled. Notes are not part of a CSV file.
std::string csv(const Table& table);

// Text for a cell of a Markdown pipe table: bars escaped ("\|") and line breaks made blanks, so that a
// label from a config or a data file can neither split nor end its row.
std::string markdown_table_cell(std::string_view text);

}  // namespace mhb
