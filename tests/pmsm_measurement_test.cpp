#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/text_file.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

// The error a parse throws, so each refusal can be checked for its file, line and column.
InputError refusal(const std::string& text) {
    try {
        parse_measurement(text, "bad.csv");
    } catch (const InputError& e) {
        return e;
    }
    FAIL("the reader accepted input it should refuse:\n" << text);
    throw std::logic_error("unreachable");
}

}  // namespace

TEST_CASE("the measurement reader takes required and optional columns", "[pmsm][measurement]") {
    const std::string text =
        "\xEF\xBB\xBFt,segment,theta_e,i_d,i_q,u_d,u_q,omega_e,temp_winding,temp_magnet,comment\r\n"
        "0,id0,0.5,0,0.1,-0.03,5.3,16.76,20,21,first\r\n"
        "0.0004, id0 ,+0.51,-0,1e-1,-3e-2,5.3,16.76,20.5,21,x\r\n"
        "\r\n"
        "0.0008,7,0.52,-0.1,0.1,-4.6,5.2,16.76,21,21,\"y\"\r\n";
    const auto m = parse_measurement(text, "ok.csv");
    REQUIRE(m.size() == 3);
    CHECK(m.i_q[1] == 0.1);
    CHECK(m.u_d[1] == -0.03);
    CHECK(m.theta_e.has_value());
    CHECK((*m.theta_e)[1] == 0.51);
    CHECK((*m.temp_winding)[1] == 20.5);
    REQUIRE(m.segment_labels == std::vector<std::string>{"id0", "7"});
    CHECK(m.segment[0] == 0);
    CHECK(m.segment[1] == 0);
    CHECK(m.segment[2] == 1);
    // The unknown column and the blank line are reported, not silently dropped.
    REQUIRE(m.warnings.size() == 2);
    CHECK(m.warnings[0].find("comment") != std::string::npos);
    CHECK(m.warnings[1].find("1 blank line") != std::string::npos);
}

TEST_CASE("the measurement reader refuses bad input, naming file, line and column", "[pmsm][measurement]") {
    SECTION("empty file") {
        const auto e = refusal(" \n\n");
        CHECK(e.file() == "bad.csv");
        CHECK(std::string(e.what()).find("empty file") != std::string::npos);
    }
    SECTION("header without rows") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n");
        CHECK(std::string(e.what()).find("no data rows") != std::string::npos);
    }
    SECTION("missing required column") {
        const auto e = refusal("i_d,i_q,u_d,omega_e\n1,2,3,4\n");
        CHECK(e.line() == 1);
        CHECK(e.field() == "u_q");
        CHECK(e.message().find("missing required column") != std::string::npos);
    }
    SECTION("duplicate column") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e,i_q\n1,2,3,4,5,6\n");
        CHECK(e.line() == 1);
        CHECK(e.field() == "i_q");
        CHECK(e.message().find("duplicate column (columns 2 and 6)") != std::string::npos);
    }
    SECTION("non-numeric value") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n1,2,3,4,5\n1,2,three,4,5\n");
        CHECK(e.line() == 3);
        CHECK(e.field() == "u_d");
        CHECK(e.message().find("not a number: 'three'") != std::string::npos);
        CHECK(std::string(e.what()) == "bad.csv:3: u_d: not a number: 'three'");
    }
    SECTION("trailing garbage after a number") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n1,2,3,4,5V\n");
        CHECK(e.line() == 2);
        CHECK(e.field() == "omega_e");
    }
    SECTION("non-finite value") {
        for (const char* bad : {"nan", "inf", "-inf", "NaN"}) {
            const auto e = refusal(std::string("i_d,i_q,u_d,u_q,omega_e,temp_magnet\n1,2,3,4,5,6\n1,2,3,4,5,") + bad + "\n");
            CHECK(e.line() == 3);
            CHECK(e.field() == "temp_magnet");
            CHECK(e.message().find("not a finite number") != std::string::npos);
        }
    }
    SECTION("empty value") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n1,,3,4,5\n");
        CHECK(e.line() == 2);
        CHECK(e.field() == "i_q");
    }
    SECTION("ragged row") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n1,2,3,4,5\n\n1,2,3,4\n");
        CHECK(e.line() == 4);
        CHECK(e.message() == "row has 4 fields but the header has 5");
    }
    SECTION("empty segment label") {
        const auto e = refusal("segment,i_d,i_q,u_d,u_q,omega_e\na,1,2,3,4,5\n ,1,2,3,4,5\n");
        CHECK(e.line() == 3);
        CHECK(e.field() == "segment");
    }
    SECTION("empty column name") {
        const auto e = refusal("i_d,,i_q,u_d,u_q,omega_e\n1,2,3,4,5,6\n");
        CHECK(e.line() == 1);
        CHECK(e.field() == "column 2");
    }
    SECTION("semicolon-separated export with decimal commas: the separator is named") {
        const auto e = refusal("i_d;i_q;u_d;u_q;omega_e\n0,1;0,2;0,3;0,4;16,7\n");
        CHECK(e.line() == 1);
        CHECK(e.field() == "i_d");
        CHECK(e.message().find("separated by ';'") != std::string::npos);
        CHECK(e.message().find("'.' as decimal point") != std::string::npos);
    }
    SECTION("decimal commas in a comma-separated file: the row has too many fields, and the hint says why") {
        const auto e = refusal("i_d,i_q,u_d,u_q,omega_e\n0,1,0,2,0,3,0,4,16,7\n");
        CHECK(e.line() == 2);
        CHECK(e.message() == "row has 10 fields but the header has 5 (a decimal comma? numbers must use '.' as the decimal mark)");
    }
    SECTION("binary input is named as such, never echoed raw") {
        const char executable_start[] = "\x7f" "ELF\x02\x01\x01\0\0\0\n\x1b[2J";
        const std::string binary(executable_start, sizeof executable_start - 1);
        const auto e = refusal(binary);
        CHECK(e.line() == 1);
        CHECK(e.message() == "binary data (a NUL byte), not a CSV text file");
        const auto escape = refusal("i_d,i_q,u_d,u_q,omega_e\n1,2,3,4,\x1b[2J\n");
        CHECK(escape.line() == 2);
        CHECK(escape.message() == "not a number: '\\x1B[2J'");
        const auto header = refusal("\x1b]0;title\x07,i_q\n1,2\n");
        CHECK(header.message().find('\x1b') == std::string::npos);
        CHECK(header.message().find("\\x1B]0;title\\x07") != std::string::npos);
    }
}

TEST_CASE("written measurements read back bit for bit", "[pmsm][measurement]") {
    Measurement m;
    const Eigen::Index n = 50;
    m.i_d = Eigen::VectorXd::LinSpaced(n, -0.1, 0.0);
    m.i_q = Eigen::VectorXd::Random(n) * 0.2;
    m.u_d = Eigen::VectorXd::Random(n) / 3.0;
    m.u_q = Eigen::VectorXd::Random(n) * 7.0;
    m.omega_e = Eigen::VectorXd::Constant(n, 16.0 * 10.0 * 2.0 * 3.141592653589793 / 60.0);
    m.t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.0004 * (n - 1));
    m.theta_e = Eigen::VectorXd::Random(n) * 3.1;
    m.theta_m = Eigen::VectorXd::Random(n) * 3.1;
    m.temp_magnet = Eigen::VectorXd::Constant(n, 1.0 / 3.0);
    m.segment_labels = {"id0", "id-0.1"};
    m.segment = Eigen::VectorXi::Zero(n);
    m.segment.tail(20).setOnes();

    const testing::TemporaryDirectory dir;
    const auto path = dir.path() / "roundtrip.csv";
    write_measurement(path, m);
    const auto back = read_measurement(path);
    CHECK(back.warnings.empty());
    CHECK(back.i_d == m.i_d);
    CHECK(back.i_q == m.i_q);
    CHECK(back.u_d == m.u_d);
    CHECK(back.u_q == m.u_q);
    CHECK(back.omega_e == m.omega_e);
    CHECK(*back.t == *m.t);
    CHECK(*back.theta_e == *m.theta_e);
    CHECK(*back.theta_m == *m.theta_m);
    CHECK(*back.temp_magnet == *m.temp_magnet);
    CHECK_FALSE(back.temp_winding.has_value());
    CHECK(back.segment_labels == m.segment_labels);
    CHECK(back.segment == m.segment);
}

TEST_CASE("the shaft angle theta_m is an optional column, in rad or deg, kept by row selection", "[pmsm][measurement]") {
    const auto map = parse_column_map("theta_m=shaft[deg]", "command line", "--columns");
    const auto m = parse_measurement("i_d,i_q,u_d,u_q,omega_e,shaft\n0,0.1,0,5,16,90\n0,0.1,0,5,16,-45\n", "m.csv", map);
    REQUIRE(m.theta_m.has_value());
    CHECK((*m.theta_m)[0] == 90.0 * (std::numbers::pi / 180.0));
    CHECK((*m.theta_m)[1] == -45.0 * (std::numbers::pi / 180.0));
    const auto second = select_rows(m, std::vector<Eigen::Index>{1});
    REQUIRE(second.theta_m.has_value());
    CHECK((*second.theta_m)[0] == (*m.theta_m)[1]);
    CHECK_FALSE(parse_measurement("i_d,i_q,u_d,u_q,omega_e\n0,0.1,0,5,16\n", "m.csv").theta_m.has_value());
}

TEST_CASE("labels that CSV cannot carry are refused by the writer", "[pmsm][measurement]") {
    Measurement m;
    m.i_d = m.i_q = m.u_d = m.u_q = m.omega_e = Eigen::VectorXd::Zero(1);
    m.segment_labels = {"a,b"};
    m.segment = Eigen::VectorXi::Zero(1);
    const testing::TemporaryDirectory dir;
    CHECK_THROWS_AS(write_measurement(dir.path() / "bad_label.csv", m), InputError);
    CHECK_FALSE(std::filesystem::exists(dir.path() / "bad_label.csv"));
}

TEST_CASE("settled rows drop the start of every segment", "[pmsm][measurement]") {
    Measurement m;
    const Eigen::Index n = 10;
    m.resize(n);
    m.t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.9);  // 0.1 s apart
    m.segment_labels = {"a", "b"};
    m.segment = Eigen::VectorXi::Zero(n);
    m.segment.tail(5).setOnes();
    const auto rows = settled_rows(m, 0.15);
    CHECK(rows == std::vector<Eigen::Index>{2, 3, 4, 7, 8, 9});
    const auto kept = select_rows(m, rows);
    CHECK(kept.size() == 6);
    CHECK((*kept.t)[3] == Approx(0.7));
    Measurement bare;
    bare.resize(3);
    CHECK_THROWS_AS(settled_rows(bare, 0.1), InputError);
    CHECK(settled_rows(bare, 0.0).size() == 3);
}

TEST_CASE("files that are no measurement are refused with what they are, before memory runs out", "[pmsm][measurement]") {
    const testing::TemporaryDirectory dir;
    try {
        read_measurement(dir.path());
        FAIL("a directory was read as a measurement");
    } catch (const InputError& e) {
        CHECK(e.file() == dir.path().string());
        CHECK_THAT(e.message(), Catch::Contains("is a directory"));
    }
    try {
        read_measurement(dir.path() / "absent.csv");
        FAIL("a missing file was read");
    } catch (const InputError& e) {
        CHECK_THAT(e.message(), Catch::Contains("No such file or directory"));
    }
    // /dev/zero never ends: reading stops at the limit instead of exhausting memory.
    try {
        read_text_file("/dev/zero", "measurement file", 1 << 20);
        FAIL("an endless file was read");
    } catch (const InputError& e) {
        CHECK_THAT(e.message(), Catch::Contains("larger than the limit of 1048576 bytes"));
    }
}

TEST_CASE("a measurement with more rows than the stated limit is refused before its columns are filled", "[pmsm][measurement]") {
    std::string text = "i_d,i_q,u_d,u_q,omega_e\n";
    text.append(static_cast<std::size_t>(max_measurement_rows) + 1, '\n');
    const auto e = refusal(text);
    CHECK_THAT(e.message(), Catch::Contains(std::to_string(max_measurement_rows + 1) + " rows") &&
                                Catch::Contains("limit is " + std::to_string(max_measurement_rows)));
}

namespace {

// A measurement with every column, its values of many lengths when written (shortest round-trip
// form), so that line ends fall everywhere in a block.
Measurement every_column(Eigen::Index n) {
    Measurement m;
    m.i_d = Eigen::VectorXd::LinSpaced(n, -0.1, 0.0);
    m.i_q = Eigen::VectorXd::Random(n) * 0.2;
    m.u_d = Eigen::VectorXd::Random(n) / 3.0;
    m.u_q = Eigen::VectorXd::Random(n) * 7.0;
    m.omega_e = Eigen::VectorXd::Constant(n, 16.76);
    m.t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.0004 * static_cast<double>(n - 1));
    m.theta_e = Eigen::VectorXd::Random(n) * 3.1;
    m.temp_winding = Eigen::VectorXd::Constant(n, 20.0) + Eigen::VectorXd::Random(n);
    m.temp_magnet = Eigen::VectorXd::Constant(n, 1.0 / 3.0);
    m.segment_labels = {"id0", "id-0.1", "iq0.25"};
    m.segment.resize(n);
    for (Eigen::Index r = 0; r < n; ++r) m.segment[r] = static_cast<int>(3 * r / n);
    return m;
}

// Compared through the writer's text: it gives every double in its shortest round-trip form, so
// equal texts mean equal doubles, and a difference shows as the row where it is.
void check_same(const Measurement& back, const Measurement& m) {
    const std::string read = format_measurement(back), written = format_measurement(m);
    const auto at = static_cast<std::size_t>(std::mismatch(read.begin(), read.end(), written.begin(), written.end()).first - read.begin());
    INFO("from byte " << at << ": read '" << read.substr(at, 80) << "', written '" << written.substr(at, 80) << "'");
    CHECK((at == read.size() && read.size() == written.size()));
}

InputError csv_file_refusal(const std::filesystem::path& path, std::size_t block_bytes) {
    try {
        read_csv_measurement(path, {}, block_bytes);
    } catch (const InputError& e) {
        return e;
    }
    FAIL("the reader accepted " << path << " read in blocks of " << block_bytes << " bytes");
    throw std::logic_error("unreachable");
}

}  // namespace

TEST_CASE("a CSV file read in blocks smaller than a line reads back bit for bit", "[pmsm][measurement]") {
    const Measurement m = every_column(3000);
    const testing::TemporaryDirectory dir;
    const auto path = dir.path() / "blocks.csv";
    write_measurement(path, m);
    REQUIRE(std::filesystem::file_size(path) > 100'000);
    for (const std::size_t block : {std::size_t{1}, std::size_t{3}, std::size_t{7}, std::size_t{64}, std::size_t{191},
                                    std::size_t{4096}, std::size_t{65'537}, csv_block_bytes}) {
        INFO("blocks of " << block << " bytes");
        const auto back = read_csv_measurement(path, {}, block);
        CHECK(back.warnings.empty());
        check_same(back, m);
    }
    check_same(read_measurement(path), m);
}

TEST_CASE("CRLF line ends, a byte-order mark and blank lines read the same wherever a block ends", "[pmsm][measurement]") {
    const std::string text =
        "\xEF\xBB\xBFt,segment,i_d,i_q,u_d,u_q,omega_e\r\n"
        "0,a,0.5,0.1,-0.03,5.3,16.76\r\n"
        "\r\n"
        "0.0004,a,+0.51,1e-1,-3e-2,5.3,16.76\r\n"
        "   \r\n"
        "0.0008,b,-0.1,0.1,-4.6,5.2,16.75\r\n"
        "0.0012,b,-0.2,0.3,-4.7,5.1,16.74";  // the last line without a line end
    const testing::TemporaryDirectory dir;
    const auto path = dir.write("crlf.csv", text);
    const auto whole = parse_measurement(text, "crlf.csv");
    REQUIRE(whole.size() == 4);
    CHECK(whole.i_d[1] == 0.51);
    CHECK((*whole.t)[3] == 0.0012);
    REQUIRE(whole.warnings.size() == 1);
    CHECK(whole.warnings[0] == "crlf.csv: 2 blank line(s) skipped");
    // Every block size up to the whole file puts a boundary between every '\r' and its '\n' somewhere.
    for (std::size_t block = 1; block <= text.size() + 1; ++block) {
        INFO("blocks of " << block << " bytes");
        const auto m = read_csv_measurement(path, {}, block);
        check_same(m, whole);
        REQUIRE(m.warnings.size() == 1);
        CHECK(m.warnings[0] == path.string() + ": 2 blank line(s) skipped");
    }
}

TEST_CASE("an error after the first block names the line it is on", "[pmsm][measurement]") {
    std::string text = "i_d,i_q,u_d,u_q,omega_e\r\n";
    for (int line = 2; line <= 2000; ++line) text += fmt::format("{},0.1,-0.03,5.3,16.76\r\n", line * 1e-4);
    const std::string bad_value = text + "0.3,0.1,three,5.3,16.76\r\n" + "0.3,0.1,-0.03,5.3,16.76\r\n";
    const std::string ragged = text + "\r\n0.3,0.1,-0.03,5.3\r\n";
    std::string nul = text + "0.3,0.1,-0.03,5.3,16.76\r\n";
    nul[nul.size() - 10] = '\0';
    const testing::TemporaryDirectory dir;
    for (const std::size_t block : {std::size_t{3}, std::size_t{64}, std::size_t{1000}, csv_block_bytes}) {
        INFO("blocks of " << block << " bytes");
        const auto value = csv_file_refusal(dir.write("value.csv", bad_value), block);
        CHECK(value.line() == 2001);
        CHECK(value.field() == "u_d");
        CHECK(value.message() == "not a number: 'three'");
        const auto row = csv_file_refusal(dir.write("ragged.csv", ragged), block);
        CHECK(row.line() == 2002);
        CHECK(row.message() == "row has 4 fields but the header has 5");
        const auto binary = csv_file_refusal(dir.write("nul.csv", nul), block);
        CHECK(binary.line() == 2001);
        CHECK(binary.message() == "binary data (a NUL byte), not a CSV text file");
    }
    // The text in memory is refused with the same words.
    CHECK(std::string(refusal(bad_value).what()) == "bad.csv:2001: u_d: not a number: 'three'");
}

TEST_CASE("a file read in blocks is refused as its text is", "[pmsm][measurement]") {
    const testing::TemporaryDirectory dir;
    for (const std::string& text : {std::string(" \n\n"), std::string("i_d,i_q,u_d,u_q,omega_e\n"), std::string("i_d,i_q,u_d,u_q,omega_e\n\n \n"),
                                   std::string("i_d,i_q,u_d,omega_e\n1,2,3,4\n"), std::string("i_d,i_q,u_d,u_q,omega_e,i_q\n1,2,3,4,5,6\n"),
                                   std::string("i_d;i_q;u_d;u_q;omega_e\n0,1;0,2;0,3;0,4;16,7\n"),
                                   std::string("segment,i_d,i_q,u_d,u_q,omega_e\na,1,2,3,4,5\n ,1,2,3,4,5\n"),
                                   std::string("i_d,i_q,u_d,u_q,omega_e\n0,1,0,2,0,3,0,4,16,7\n"), std::string("i_d,i_q,u_d,u_q,omega_e\n1,2,3,4,1e999\n")}) {
        const auto path = dir.write("bad.csv", text);
        const auto expected = refusal(text);
        for (const std::size_t block : {std::size_t{1}, std::size_t{4}, std::size_t{9}, csv_block_bytes}) {
            INFO(text << "in blocks of " << block << " bytes");
            const auto e = csv_file_refusal(path, block);
            CHECK(e.line() == expected.line());
            CHECK(e.field() == expected.field());
            CHECK(e.message() == expected.message());
        }
    }
}

TEST_CASE("selecting the rows of a measurement no longer needed gives what a copy gives", "[pmsm][measurement]") {
    const Measurement m = every_column(40);
    for (const std::vector<Eigen::Index>& rows : {std::vector<Eigen::Index>{0, 1, 2, 39}, std::vector<Eigen::Index>{15, 16, 30, 31, 32},
                                                  std::vector<Eigen::Index>{}, std::vector<Eigen::Index>{3, 2, 1},
                                                  std::vector<Eigen::Index>{5, 5, 6}, settled_rows(m, 0.0)}) {
        INFO(rows.size() << " rows");
        const Measurement copied = select_rows(m, rows);
        Measurement spent = m;
        check_same(select_rows(std::move(spent), rows), copied);
    }
    // The rows after the middle segment's start: its label comes first, the first segment's is gone.
    const auto tail = select_rows(every_column(40), std::vector<Eigen::Index>{20, 30, 39});
    CHECK(tail.segment_labels == std::vector<std::string>{"id-0.1", "iq0.25"});
    CHECK(tail.segment == Eigen::Vector3i(0, 1, 1));
}
