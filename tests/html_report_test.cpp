// The HTML report writer: one self-contained page that escapes every text, marks numbers for sorting
// and inlines the plots.
#include <catch2/catch.hpp>

#include <filesystem>

#include "framework/html_report.hpp"
#include "framework/input_error.hpp"
#include "framework/plots.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
namespace fs = std::filesystem;

namespace {

std::size_t occurrences(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
    return n;
}

const std::string hostile = "<script>alert('x')</script> & \"q\"";
const std::string hostile_escaped = "&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; &quot;q&quot;";

// What a page may not do to stay self-contained: load a script, a style sheet, an image, a frame or a
// font from anywhere. The only URLs are the SVG and XLink namespace names, which identify and are
// never fetched.
void check_self_contained(const std::string& html) {
    for (const char* tag : {"<script src", "<link", "<img", "<iframe", "<object", "<embed", "@import", "url(http", "@font-face"})
        CHECK(html.find(tag) == std::string::npos);
    std::string stripped = html;
    for (const std::string ns : {"http://www.w3.org/2000/svg", "http://www.w3.org/1999/xlink"})
        for (auto at = stripped.find(ns); at != std::string::npos; at = stripped.find(ns)) stripped.erase(at, ns.size());
    CHECK(stripped.find("http://") == std::string::npos);
    CHECK(stripped.find("https://") == std::string::npos);
    // One script: the page's own, inline.
    CHECK(occurrences(html, "<script") == 1);
    CHECK(occurrences(html, "<script>\n(function () {") == 1);
}

}  // namespace

TEST_CASE("html_escape escapes markup and both quotes", "[html_report]") {
    CHECK(html_escape(hostile) == hostile_escaped);
    CHECK(html_escape("plain text, 1.5e-05 ± 2 %") == "plain text, 1.5e-05 ± 2 %");
}

TEST_CASE("a page escapes user text wherever it goes and runs only its own script", "[html_report]") {
    HtmlReport page(hostile);
    page.add_provenance(hostile, hostile);
    page.add_heading(2, hostile);
    page.add_paragraph(hostile);
    page.add_list({hostile});
    page.add_preformatted(hostile);
    page.add_table({{"label", hostile}, {{hostile, "1"}}});
    page.add_details(hostile, hostile);
    const std::string html = page.html();
    CHECK(html.find("alert('x')") == std::string::npos);
    // <title> and <h1>, provenance label and value, heading, paragraph, item, preformatted, header, cell,
    // summary and details.
    CHECK(occurrences(html, hostile_escaped) == 12);
    check_self_contained(html);
}

TEST_CASE("a page's inline markup: `code` and **bold**, and a lone marker stays text", "[html_report]") {
    HtmlReport page;
    page.add_paragraph("**Recommended model: `base+encoder_offset`** (a `<b>` tag), 2 ** 3 and a ` alone");
    const std::string html = page.html();
    CHECK(html.find("<p><strong>Recommended model: <code>base+encoder_offset</code></strong> (a <code>&lt;b&gt;</code> tag), 2 ** 3 and a ` alone</p>") !=
          std::string::npos);
}

TEST_CASE("table cells that hold numbers carry their sort key and missing values an empty one", "[html_report]") {
    HtmlReport page;
    page.add_table({{"optimizer", "mean", "runs", "A12", "note"},
                    {{"gwo", "1.5e-05", "10 (2 failed)", "0.50 (large)", "2opt"},
                     {"soa", "–", "3", "—", "-"},
                     {"de", "inf", "", "-inf", "12 %"},
                     {"short row"}}});
    const std::string html = page.html();
    CHECK(page.table_count() == 1);
    CHECK(html.find("<th scope=\"col\">optimizer</th><th scope=\"col\">mean</th>") != std::string::npos);
    CHECK(html.find("<td>gwo</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"1.5e-05\">1.5e-05</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"10\">10 (2 failed)</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"0.5\">0.50 (large)</td>") != std::string::npos);
    CHECK(html.find("<td>2opt</td>") != std::string::npos);  // a word that starts with a digit
    CHECK(html.find("<td class=\"number\" data-sort=\"\">–</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"\">—</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"Infinity\">inf</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"-Infinity\">-inf</td>") != std::string::npos);
    CHECK(html.find("<td class=\"number\" data-sort=\"12\">12 %</td>") != std::string::npos);
    // The short row is padded to the header's five columns.
    CHECK(html.find("<tr><td>short row</td><td class=\"number\" data-sort=\"\"></td><td class=\"number\" data-sort=\"\"></td>"
                    "<td class=\"number\" data-sort=\"\"></td><td class=\"number\" data-sort=\"\"></td></tr>") != std::string::npos);
}

TEST_CASE("inline_svg drops the prolog, scales by the viewBox and keeps each plot's ids its own", "[html_report]") {
    const std::string svg =
        "<?xml version=\"1.0\" encoding=\"utf-8\" standalone=\"no\"?>\n"
        "<!DOCTYPE svg PUBLIC \"-//W3C//DTD SVG 1.1//EN\" \"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd\">\n"
        "<!-- drawn by hand -->\n"
        "<svg width=\"600px\" height='400' xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\">\n"
        "<defs><path id='gpPt0' d='M-1,0 h2'/><linearGradient id=\"fade\"/></defs>\n"
        "<use xlink:href='#gpPt0' stroke='#1b9e77'/><rect fill=\"url(#fade)\" stroke=\"#fade00\"/>\n"
        "</svg>\n";
    const std::string inlined = inline_svg(svg, "plot3-", "hand.svg");
    CHECK(inlined.starts_with("<svg "));
    CHECK(inlined.ends_with("</svg>"));
    CHECK(inlined.find("<?xml") == std::string::npos);
    CHECK(inlined.find("DOCTYPE") == std::string::npos);
    CHECK(inlined.find("svg11.dtd") == std::string::npos);
    CHECK(inlined.find("viewBox=\"0 0 600 400\"") != std::string::npos);
    CHECK(inlined.find("style=\"max-width: 750px\"") != std::string::npos);
    CHECK(inlined.find("width=\"600px\"") == std::string::npos);
    CHECK(inlined.find("height='400'") == std::string::npos);
    CHECK(inlined.find("id='plot3-gpPt0'") != std::string::npos);
    CHECK(inlined.find("xlink:href='#plot3-gpPt0'") != std::string::npos);
    CHECK(inlined.find("id=\"plot3-fade\"") != std::string::npos);
    CHECK(inlined.find("url(#plot3-fade)") != std::string::npos);
    // Colours are not ids, even one that starts like an id.
    CHECK(inlined.find("stroke='#1b9e77'") != std::string::npos);
    CHECK(inlined.find("stroke=\"#fade00\"") != std::string::npos);
}

TEST_CASE("gnuplot's own SVG inlines with its viewBox", "[html_report][plots]") {
    mhb::testing::TemporaryDirectory dir;
    std::string error;
    REQUIRE(render_gnuplot(dir.path() / "curve", "set title 'a <title> & more' noenhanced\nplot sin(x) with points pt 7\n", 640, 400, error));
    HtmlReport page;
    page.add_plot(dir.path() / "curve.svg", "curve.png");
    const std::string html = page.html();
    CHECK(page.plot_count() == 1);
    CHECK(html.find("<?xml") == std::string::npos);
    CHECK(html.find("viewBox=\"0 0 640 400\"") != std::string::npos);
    CHECK(html.find("a &lt;title> &amp; more") != std::string::npos);  // gnuplot's escaping, kept
    CHECK(html.find("href='#plot1-gpPt6'") != std::string::npos);
    check_self_contained(html);
}

TEST_CASE("inline_svg and add_plot refuse what they cannot show, naming the file", "[html_report]") {
    using Catch::Matchers::Contains;
    CHECK_THROWS_WITH(inline_svg("<html><body>no drawing</body></html>", "p-", "page.svg"), Contains("page.svg") && Contains("no <svg> element"));
    CHECK_THROWS_WITH(inline_svg("<svg viewBox='0 0 1 1'><script>alert(1)</script></svg>", "p-", "active.svg"), Contains("holds a script"));
    CHECK_THROWS_WITH(inline_svg("<svg><rect/></svg>", "p-", "sizeless.svg"), Contains("neither a viewBox nor a width and height"));
    CHECK_THROWS_WITH(inline_svg("<svg viewBox='0 0 wide tall'><rect/></svg>", "p-", "odd.svg"), Contains("is not four numbers"));
    HtmlReport page;
    CHECK_THROWS_AS(page.add_plot("/nonexistent/plot.svg", "gone"), InputError);
    CHECK_THROWS_WITH(page.add_plot("/nonexistent/plot.svg", "gone"), Contains("/nonexistent/plot.svg"));
}

TEST_CASE("add_markdown reads the Markdown the reports are written in", "[html_report]") {
    mhb::testing::TemporaryDirectory dir;
    dir.write("bars.svg", "<svg viewBox=\"0 0 300 200\"><rect width=\"10\" height=\"20\"/></svg>");
    const std::string markdown =
        "# Diagnosis of `base`\n\n"
        "Intro over\ntwo lines.\n\n"
        "## What it says\n\n"
        "- first finding\n- second **finding**\n\n"
        "| segment | rms (mV) |\n|---|---|\n| a\\|b | 1.5 |\n| c | – |\n\n"
        "![residual per segment](bars.png)\n\n"
        "Next step:\n\n    mhbench fit --data d.csv\n    mhbench diagnose --data d.csv\n\n"
        "### Detail\n\n#not-a-heading stays text\n";
    HtmlReport page;
    page.add_markdown(markdown, dir.path());
    const std::string html = page.html();
    CHECK(html.find("<title>Diagnosis of `base`</title>") != std::string::npos);
    CHECK(html.find("<h1>Diagnosis of <code>base</code></h1>") != std::string::npos);
    CHECK(html.find("<p>Intro over two lines.</p>") != std::string::npos);
    CHECK(html.find("<h2 id=\"section-1\">What it says</h2>") != std::string::npos);
    CHECK(html.find("<li>second <strong>finding</strong></li>") != std::string::npos);
    CHECK(html.find("<td>a|b</td><td class=\"number\" data-sort=\"1.5\">1.5</td>") != std::string::npos);
    CHECK(page.table_count() == 1);
    CHECK(page.plot_count() == 1);
    CHECK(html.find("<figcaption>residual per segment</figcaption>") != std::string::npos);
    CHECK(html.find("<pre>mhbench fit --data d.csv\nmhbench diagnose --data d.csv</pre>") != std::string::npos);
    CHECK(html.find("<h3 id=\"section-2\">Detail</h3>") != std::string::npos);
    CHECK(html.find("<p>#not-a-heading stays text</p>") != std::string::npos);
    // An image whose SVG is missing is an error naming it, not a silently missing plot.
    HtmlReport broken;
    CHECK_THROWS_WITH(broken.add_markdown("![gone](gone.png)\n", dir.path()), Catch::Matchers::Contains("gone.svg"));
}

TEST_CASE("markdown_table_cell keeps a label in its cell, and add_markdown reads it back whole", "[html_report]") {
    CHECK(markdown_table_cell("a|b\nc\r\nd") == "a\\|b c  d");
    HtmlReport page;
    page.add_markdown("| label | x |\n|---|---|\n| " + markdown_table_cell("rs|de") + " | 1 |\n", ".");
    CHECK(page.html().find("<td>rs|de</td><td class=\"number\" data-sort=\"1\">1</td></tr>") != std::string::npos);
}
