// report.html: one self-contained page per results directory and per diagnosis. The writer escapes
// every text, marks numbers for sorting and inlines the plots; headless Chromium (the Debian package,
// which CI installs) then shows that real reports render: not blank, with their tables and plots,
// and that a click on a header sorts.
#include <catch2/catch.hpp>

#include <png.h>

#include <filesystem>
#include <regex>
#include <set>

#include "framework/html_report.hpp"
#include "framework/input_error.hpp"
#include "framework/plots.hpp"
#include "framework/process.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

namespace {

Table table_of(std::vector<Column> columns, const std::vector<std::vector<Cell>>& rows) {
    Table table("test table", std::move(columns));
    for (const auto& row : rows) table.add_row(row);
    return table;
}

}  // namespace
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

// ---- headless Chromium ----

const fs::path chromium = "/usr/bin/chromium";

// Fails (not skips) without the browser: CI installs it, so a missing one is a broken setup.
void require_chromium() {
    if (!fs::exists(chromium))
        FAIL("headless Chromium is needed at " + chromium.string() +
             " to check that the HTML reports render: install the Debian package chromium (.ci/install-dependencies does)");
}

// Runs Chromium on `page` with `mode` (--screenshot=FILE or --dump-dom), a fresh profile each time and
// a time limit; its standard output goes to `output`, its chatter on standard error is ignored.
void run_chromium(const fs::path& page, const std::string& mode, const fs::path& output) {
    mhb::testing::TemporaryDirectory profile;
    const auto run = run_program({"timeout", "--kill-after=5", "60", chromium.string(), "--headless", "--no-sandbox", "--disable-gpu",
                                  "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update",
                                  "--disable-sync", "--user-data-dir=" + profile.path().string(), "--window-size=1280,2400", mode,
                                  "file://" + fs::absolute(page).string()},
                                 std::nullopt, output, profile.path() / "chromium-stderr.txt");
    INFO("chromium " << mode << " " << page << ": " << run.error << "\n" << mhb::testing::read_file(profile.path() / "chromium-stderr.txt"));
    REQUIRE(run.started);
    REQUIRE(run.exit_code == 0);  // 124: the time limit ran out
}

// The page as Chromium holds it once its script has run.
std::string rendered_dom(const fs::path& page, const fs::path& scratch) {
    const fs::path dom = scratch / (page.stem().string() + "-dom.html");
    run_chromium(page, "--dump-dom", dom);
    return mhb::testing::read_file(dom);
}

struct Rgb {
    int r, g, b;
};

struct Screenshot {
    unsigned width = 0, height = 0;
    double ink = 0;         // share of pixels that are not white
    std::size_t tones = 0;  // distinct colours
    std::size_t plotted = 0;  // pixels in the colour of a plotted line (Screenshot::line), which no text or table uses
};

Screenshot screenshot(const fs::path& page, const fs::path& png, Rgb line) {
    run_chromium(page, "--screenshot=" + png.string(), png.string() + ".log");
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    INFO(png);
    REQUIRE(png_image_begin_read_from_file(&image, png.c_str()) != 0);
    image.format = PNG_FORMAT_RGB;
    std::vector<png_byte> pixels(PNG_IMAGE_SIZE(image));
    REQUIRE(png_image_finish_read(&image, nullptr, pixels.data(), 0, nullptr) != 0);
    Screenshot s;
    s.width = image.width;
    s.height = image.height;
    std::size_t ink = 0;
    std::set<std::uint32_t> tones;
    for (std::size_t i = 0; i + 2 < pixels.size(); i += 3) {
        const int r = pixels[i], g = pixels[i + 1], b = pixels[i + 2];
        if (std::min({r, g, b}) < 240) ++ink;
        if (std::abs(r - line.r) <= 12 && std::abs(g - line.g) <= 12 && std::abs(b - line.b) <= 12) ++s.plotted;
        tones.insert(static_cast<std::uint32_t>(r << 16 | g << 8 | b));
    }
    s.ink = static_cast<double>(ink) / static_cast<double>(pixels.size() / 3);
    s.tones = tones.size();
    return s;
}

// A report's screenshot at a laptop's width: the page is drawn, with text, tables and at least one plot.
void check_drawn(const Screenshot& s) {
    INFO("ink " << s.ink << ", " << s.tones << " colours, " << s.plotted << " pixels of a plotted line");
    CHECK(s.width == 1280);
    CHECK(s.height == 2400);
    CHECK(s.ink > 0.03);
    CHECK(s.tones > 200);
    CHECK(s.plotted > 300);
}

// Every <table> and every <svg> the file holds is in the DOM, and the script made each table sortable.
void check_dom(const std::string& html, const std::string& dom, std::size_t tables, std::size_t plots) {
    CHECK(occurrences(html, "<table>") == tables);
    CHECK(occurrences(dom, "<table") == tables);
    CHECK(occurrences(dom, "<table class=\"sortable\">") == tables);
    CHECK(occurrences(html, "<svg ") == plots);
    CHECK(occurrences(dom, "<svg ") == plots);
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
    page.add_table(table_of({"label", hostile}, {{hostile, "1"}}));
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
    page.add_table(table_of({"optimizer", Column("mean", "s"), "runs", "A12", "note"},
                            {{"gwo", "1.5e-05", "10 (2 failed)", "0.50 (large)", "2opt"},
                             {"soa", "–", "3", "—", "-"},
                             {"de", "inf", "", "-inf", "12 %"},
                             {"blank", Cell::none(), Cell::none(), "", Cell::none()}}));
    const std::string html = page.html();
    CHECK(page.table_count() == 1);
    CHECK(html.find("<th scope=\"col\">optimizer</th><th scope=\"col\">mean (s)</th>") != std::string::npos);
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
    // Blank slots and empty text are both missing values.
    CHECK(html.find("<tr><td>blank</td><td class=\"number\" data-sort=\"\"></td><td class=\"number\" data-sort=\"\"></td>"
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

TEST_CASE("add_document shows each block of a report", "[html_report]") {
    mhb::testing::TemporaryDirectory dir;
    dir.write("bars.svg", "<svg viewBox=\"0 0 300 200\"><rect width=\"10\" height=\"20\"/></svg>");
    Document doc;
    doc.add(Heading{1, "Diagnosis of `base`"});
    doc.add(Paragraph{"Intro over\ntwo lines."});
    doc.add(Heading{2, "What it says"});
    doc.add(BulletList{{"first finding", "second **finding**"}});
    Table table("segments", {"segment", Column("rms", "mV")});
    table.add_row({"a|b", "1.5"});
    table.add_row({"c", "–"});
    table.add_note("Noise **floor** 0.2 mV.");
    doc.add(std::move(table));
    doc.add(Image{"bars.png", "residual per segment"});
    doc.add(Paragraph{"Next step:"});
    doc.add(Preformatted{"mhbench fit --data d.csv\nmhbench diagnose --data d.csv"});
    doc.add(Heading{3, "Detail"});
    doc.add(Paragraph{"#not-a-heading stays text"});
    doc.add(BulletList{});
    HtmlReport page;
    page.add_document(doc, dir.path());
    const std::string html = page.html();
    CHECK(html.find("<title>Diagnosis of `base`</title>") != std::string::npos);
    CHECK(html.find("<h1>Diagnosis of <code>base</code></h1>") != std::string::npos);
    CHECK(html.find("<p>Intro over two lines.</p>") != std::string::npos);
    CHECK(html.find("<h2 id=\"section-1\">What it says</h2>") != std::string::npos);
    CHECK(html.find("<li>second <strong>finding</strong></li>") != std::string::npos);
    CHECK(html.find("<th scope=\"col\">segment</th><th scope=\"col\">rms (mV)</th>") != std::string::npos);
    CHECK(html.find("<td>a|b</td><td class=\"number\" data-sort=\"1.5\">1.5</td>") != std::string::npos);
    CHECK(html.find("</table></div>\n<p>Noise <strong>floor</strong> 0.2 mV.</p>") != std::string::npos);
    CHECK(page.table_count() == 1);
    CHECK(page.plot_count() == 1);
    CHECK(html.find("<figcaption>residual per segment</figcaption>") != std::string::npos);
    CHECK(html.find("<pre>mhbench fit --data d.csv\nmhbench diagnose --data d.csv</pre>") != std::string::npos);
    CHECK(html.find("<h3 id=\"section-2\">Detail</h3>") != std::string::npos);
    CHECK(html.find("<p>#not-a-heading stays text</p>") != std::string::npos);
    CHECK(occurrences(html, "<ul>") == 1);  // the empty list shows nothing
    // An image whose SVG is missing is an error naming it, not a silently missing plot.
    Document gone;
    gone.add(Image{"gone.png", "gone"});
    HtmlReport broken;
    CHECK_THROWS_WITH(broken.add_document(gone, dir.path()), Catch::Matchers::Contains("gone.svg"));
}

TEST_CASE("mhbench run writes report.html that renders in headless Chromium with its tables and plots", "[html_report][cli][browser]") {
    require_chromium();
    mhb::testing::TemporaryDirectory dir;
    // Labels and a description with markup in them, as a user's config may have.
    const auto config = dir.write("tiny.toml",
                                  "name = \"tiny <report>\"\n"
                                  "description = \"Two optimisers & two problems; <b>not bold</b>.\"\n"
                                  "trials = 4\nseed = 7\noutput = \"out\"\n[budget]\nevaluations = 800\n"
                                  "[[optimizer]]\nname = \"random_search\"\nlabel = \"rs <script>alert(1)</script>\"\n"
                                  "[[optimizer]]\nname = \"de\"\n"
                                  "[[problem]]\nname = \"F1\"\ndimension = 5\n[[problem]]\nname = \"bbob_f3\"\ndimension = 5\n");
    const auto run = mhb::testing::run_mhbench({"run", config.string(), "--threads", "2"}, dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    CHECK(run.output.find("table.md, table.csv, report.html and 4 plots") != std::string::npos);
    const fs::path report = dir.path() / "out" / "report.html";
    REQUIRE(fs::exists(report));
    const std::string html = mhb::testing::read_file(report);
    check_self_contained(html);
    CHECK(html.find("<title>tiny &lt;report&gt;</title>") != std::string::npos);
    CHECK(html.find("rs &lt;script&gt;alert(1)&lt;/script&gt;") != std::string::npos);
    CHECK(html.find("<script>alert(1)") == std::string::npos);
    // Provenance, and the config as the run read it.
    for (const char* label : {"<dt>mhbench</dt>", "<dt>commit</dt>", "<dt>date</dt>", "<dt>machine</dt>", "<dt>threads</dt><dd>2</dd>"})
        CHECK(html.find(label) != std::string::npos);
    CHECK(html.find("<summary><code>tiny.toml</code> as the run read it</summary>") != std::string::npos);
    CHECK(html.find("label = &quot;rs &lt;script&gt;alert(1)&lt;/script&gt;&quot;") != std::string::npos);

    // A table per problem and the Friedman ranks; a convergence plot and a box plot per problem.
    const std::string dom = rendered_dom(report, dir.path());
    check_dom(html, dom, 3, 4);
    // de's median line: the second optimiser's colour in framework/plots.cpp.
    check_drawn(screenshot(report, dir.path() / "run-report.png", {0xd9, 0x5f, 0x02}));

    // `mhbench table` remakes it; without plots it says so.
    const auto table = mhb::testing::run_mhbench({"table", (dir.path() / "out").string(), "--no-plots"}, dir.path() / "log2");
    REQUIRE(table.exit_code == 0);
    CHECK(table.output.find("table.md, table.csv, report.html.") != std::string::npos);
    const std::string without = mhb::testing::read_file(report);
    CHECK(occurrences(without, "<svg ") == 0);
    CHECK(without.find("No plots: they were not drawn (--no-plots).") != std::string::npos);
}

TEST_CASE("mhbench diagnose --report writes report.html that renders in headless Chromium with its tables and plots",
          "[html_report][pmsm][cli][browser]") {
    require_chromium();
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "hidden.csv";
    pmsm::write_measurement(csv, pmsm::testing::diagnosis_data({{"encoder_offset", {}}}));
    const auto report = dir.path() / "report";
    const auto run = pmsm::testing::run_mhbench("diagnose --data " + csv.string() + " --model base --threads 2 --report " + report.string(),
                                               dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    const fs::path page = report / "report.html";
    REQUIRE(fs::exists(page));
    const std::string html = mhb::testing::read_file(page);
    check_self_contained(html);
    CHECK(html.find("<title>Diagnosis of `base` on `" + csv.string() + "`</title>") != std::string::npos);
    CHECK(html.find("Missing effect: encoder_offset") != std::string::npos);
    CHECK(html.find("<dt>threads</dt><dd>2</dd>") != std::string::npos);
    CHECK(html.find("<dt>data</dt><dd>" + csv.string() + "</dd>") != std::string::npos);

    // Every table and every image of report.md is on the page.
    const std::string md = mhb::testing::read_file(report / "report.md");
    const std::regex table_rule(R"(\n\|---)");
    const auto tables = static_cast<std::size_t>(std::distance(std::sregex_iterator(md.begin(), md.end(), table_rule), std::sregex_iterator()));
    const std::size_t plots = occurrences(md, "![");
    CHECK(tables >= 6);
    CHECK(plots == 9);
    const std::string dom = rendered_dom(page, dir.path());
    check_dom(html, dom, tables, plots);
    // The fitted model's colour in problems/pmsm/report/diagnosis_report.cpp.
    check_drawn(screenshot(page, dir.path() / "diagnosis-report.png", {0x1b, 0x6f, 0xb5}));
}

TEST_CASE("a click on a header sorts numbers as numbers with missing values last, and a second click reverses", "[html_report][browser]") {
    require_chromium();
    mhb::testing::TemporaryDirectory dir;
    HtmlReport page("sorting");
    page.add_table(table_of({"optimizer", "error"}, {{"b", "10"}, {"a", "9"}, {"d", "–"}, {"c", "1e-3"}, {"B", "-inf"}}));
    // The test clicks as a reader would, then writes the row order where --dump-dom shows it.
    const std::string clicks = R"(<script>
var table = document.querySelector('table'), out = [];
function order() { return Array.prototype.map.call(table.tBodies[0].rows, function (r) { return r.cells[0].textContent; }).join(','); }
var headers = table.tHead.rows[0].cells;
headers[1].click(); out.push(order());
headers[1].click(); out.push(order());
headers[0].click(); out.push(order());
document.body.setAttribute('data-orders', out.join(' '));
</script>
)";
    std::string html = page.html();
    html.insert(html.rfind("</body>"), clicks);
    const auto file = dir.write("sorting.html", html);
    const std::string dom = rendered_dom(file, dir.path());
    CHECK(dom.find("data-orders=\"B,c,a,b,d b,a,c,B,d a,b,B,c,d\"") != std::string::npos);
    CHECK(dom.find("aria-sort=\"ascending\"") != std::string::npos);
}
