// The structured report content and its Markdown, CSV and HTML writers.
#include <catch2/catch.hpp>

#include <stdexcept>

#include "framework/html_report.hpp"
#include "framework/report_document.hpp"

using namespace mhb;

namespace {

// Units in the header, a blank slot beside an empty text, a bar, markup characters and a comma in
// cells, and a note.
Table sample_table() {
    Table table("final error", {"optimizer", Column("mean", "V"), Column("time", "s"), "note"});
    table.add_row({"gwo", "1.5e-05", "0.25", "plain"});
    table.add_row({"rs|de", "–", Cell::none(), ""});
    table.add_row({"<b> & co", "2", "1", "a, \"quoted\" word"});
    table.add_note("Times are per trial.");
    return table;
}

}  // namespace

TEST_CASE("a table renders to Markdown with units, escaped bars, blank slots and its notes", "[report_document]") {
    CHECK(markdown(sample_table()) ==
          "| optimizer | mean (V) | time (s) | note |\n"
          "|---|---|---|---|\n"
          "| gwo | 1.5e-05 | 0.25 | plain |\n"
          "| rs\\|de | – | |  |\n"
          "| <b> & co | 2 | 1 | a, \"quoted\" word |\n"
          "\n"
          "Times are per trial.\n");
}

TEST_CASE("a table renders to CSV with commas, quotes and line breaks quoted and no notes", "[report_document]") {
    CHECK(csv(sample_table()) ==
          "optimizer,mean (V),time (s),note\n"
          "gwo,1.5e-05,0.25,plain\n"
          "rs|de,–,,\n"
          "<b> & co,2,1,\"a, \"\"quoted\"\" word\"\n");
    Table lines("lines", {"label, with comma", "text"});
    lines.add_row({"two\nlines", "x"});
    CHECK(csv(lines) == "\"label, with comma\",text\n\"two\nlines\",x\n");
}

TEST_CASE("a table renders to HTML with units in the header, escaped cells and its notes after it", "[report_document]") {
    HtmlReport page;
    page.add_table(sample_table());
    const std::string html = page.html();
    CHECK(html.find("<thead><tr><th scope=\"col\">optimizer</th><th scope=\"col\">mean (V)</th><th scope=\"col\">time (s)</th>"
                    "<th scope=\"col\">note</th></tr></thead>\n<tbody>\n"
                    "<tr><td>gwo</td><td class=\"number\" data-sort=\"1.5e-05\">1.5e-05</td><td class=\"number\" data-sort=\"0.25\">0.25</td>"
                    "<td>plain</td></tr>\n"
                    "<tr><td>rs|de</td><td class=\"number\" data-sort=\"\">–</td><td class=\"number\" data-sort=\"\"></td>"
                    "<td class=\"number\" data-sort=\"\"></td></tr>\n"
                    "<tr><td>&lt;b&gt; &amp; co</td><td class=\"number\" data-sort=\"2\">2</td><td class=\"number\" data-sort=\"1\">1</td>"
                    "<td>a, &quot;quoted&quot; word</td></tr>\n"
                    "</tbody>\n</table></div>\n<p>Times are per trial.</p>\n") != std::string::npos);
}

TEST_CASE("a row whose cell count differs from the columns' is refused", "[report_document]") {
    Table table("final error", {"optimizer", "mean"});
    CHECK_THROWS_AS(table.add_row({"gwo"}), std::invalid_argument);
    CHECK_THROWS_WITH(table.add_row({"gwo", "1", "2"}), Catch::Matchers::Contains("final error") && Catch::Matchers::Contains("3 cells for 2 columns"));
    CHECK(table.rows().empty());
    table.add_row({"gwo", "1"});
    CHECK(table.rows().size() == 1);
}

TEST_CASE("a document renders to Markdown as blocks separated by blank lines", "[report_document]") {
    Document doc;
    doc.add(Heading{1, "Diagnosis of `base`"});
    doc.add(Paragraph{"**Recommended model: `base+x`**"});
    Table table("steps", {"", Column("rms", "mV")});
    table.add_row({"start", "1.50"});
    doc.add(std::move(table));
    doc.add(BulletList{{"first", "second"}});
    doc.add(BulletList{});
    doc.add(Image{"path.png", "residual after each step"});
    doc.add(Preformatted{"mhbench fit\nmhbench diagnose"});
    doc.add(Heading{3, "Detail"});
    Document more;
    more.add(Paragraph{"Total: 3 trials."});
    doc.append(more);
    CHECK(markdown(doc) ==
          "# Diagnosis of `base`\n"
          "\n"
          "**Recommended model: `base+x`**\n"
          "\n"
          "| | rms (mV) |\n"
          "|---|---|\n"
          "| start | 1.50 |\n"
          "\n"
          "- first\n"
          "- second\n"
          "\n"
          "\n"
          "![residual after each step](path.png)\n"
          "\n"
          "    mhbench fit\n"
          "    mhbench diagnose\n"
          "\n"
          "### Detail\n"
          "\n"
          "Total: 3 trials.\n");
}

TEST_CASE("markdown_table_cell keeps a label in its cell", "[report_document]") {
    CHECK(markdown_table_cell("a|b\nc\r\nd") == "a\\|b c  d");
    CHECK(markdown_table_cell("plain") == "plain");
}
