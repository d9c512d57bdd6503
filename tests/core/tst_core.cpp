// The shared vocabulary: strict numbers and lengths, JSON with limits, field
// readers that name the field, atomic writes, the work-sharing loop, text
// from users (UTF-8, NFC, names, echoing untrusted text).
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <QTemporaryDir>
#include <QTest>

#include <atomic>
#include <fstream>

using namespace drape;
using nlohmann::json;

namespace {
template <class E, class F>
QString error_of(F&& f)
{
    try {
        f();
    } catch (const E& e) {
        return QString::fromStdString(e.what());
    }
    return {};
}
} // namespace

class TestCore : public QObject {
    Q_OBJECT
private slots:
    void numbers_are_parsed_strictly()
    {
        double v = 0;
        QVERIFY(parse_number("81.5", v) && v == 81.5);
        QVERIFY(parse_number("  -2e-3 ", v) && v == -2e-3);
        QVERIFY(parse_number("+7", v) && v == 7);
        for (const char* bad : {"81.5abc", "", " ", "nan", "inf", "1e400", "0x10", "1,5", "--1"}) {
            double w = 42;
            QVERIFY2(!parse_number(bad, w), bad);
            QCOMPARE(w, 42.0); // untouched on failure
        }
    }

    void lengths_take_units()
    {
        QCOMPARE(parse_length("300mm", "--x"), 0.3);
        QCOMPARE(parse_length("30 cm", "--x"), 0.3);
        QCOMPARE(parse_length("0.3", "--x"), 0.3);
        const QString e = error_of<ParameterError>([] { parse_length("3 furlongs", "--disc-diameter"); });
        QVERIFY2(e.contains("--disc-diameter") && e.contains("furlongs"), qPrintable(e));
        QVERIFY(!error_of<ParameterError>([] { parse_length("1e400mm", "--x"); }).isEmpty());
    }

    void values_in_messages_read_as_written()
    {
        QCOMPARE(QString::fromStdString(format_value(0.08)), QString("0.08"));
        QCOMPARE(QString::fromStdString(format_double(0.1)), QString("0.10000000000000001")); // files: exact round trip
    }

    void json_has_depth_and_range_limits()
    {
        QVERIFY(parse_json(R"({"a":[1,2,{"b":3}]})", "x").is_object());
        const std::string deep = std::string(100000, '[') + std::string(100000, ']');
        QString e = error_of<FileError>([&] { parse_json(deep, "deep.json"); });
        QVERIFY2(e.contains("deep.json") && e.contains("nested deeper"), qPrintable(e));
        e = error_of<FileError>([] { parse_json("{\n  \"x\": 1e400}", "big.json"); });
        QVERIFY2(e.contains("big.json: line 2, column 8: the number 1e400 is outside the range of a double"), qPrintable(e));
        e = error_of<FileError>([] { parse_json("{\"x\": \"\xff\xfe\"}", "utf.json"); });
        QVERIFY2(e.contains("utf.json") && e.contains("not valid JSON"), qPrintable(e));
        e = error_of<FileError>([] { parse_json("{ \"x\": ", "cut.json"); });
        QVERIFY2(e.contains("cut.json") && e.contains("not valid JSON"), qPrintable(e));
    }

    void field_reader_names_the_field_and_value()
    {
        const json j = json::parse(R"({"a":{"b":"x","n":-3,"k":2.5,"v":[1,"two"]}})");
        const JsonReader r("meta.json");
        QString e = error_of<FileError>([&] { r.number(j, "a.b"); });
        QVERIFY2(e.contains("meta.json") && e.contains("'a.b'") && e.contains("\"x\""), qPrintable(e));
        e = error_of<FileError>([&] { r.positive(j, "a.n"); });
        QVERIFY2(e.contains("'a.n'") && e.contains("-3"), qPrintable(e));
        e = error_of<FileError>([&] { r.integer(j, "a.k", 0); });
        QVERIFY2(e.contains("'a.k'") && e.contains("integer"), qPrintable(e));
        e = error_of<FileError>([&] { r.number_in(j, "a.n", 0, 10, "mm"); });
        QVERIFY2(e.contains("-3 mm") && e.contains("[0, 10] mm"), qPrintable(e));
        e = error_of<FileError>([&] { r.numbers(j, "a.v", 0); });
        QVERIFY2(e.contains("'a.v[1]'"), qPrintable(e));
        e = error_of<FileError>([&] { r.need(j, "a.missing"); });
        QVERIFY2(e.contains("'a.missing' is missing"), qPrintable(e));
        QVERIFY(!r.optional_number(j, "a.none"));
    }

    void files_are_read_with_a_limit_and_written_atomically()
    {
        QTemporaryDir d;
        const std::string p = d.filePath("f.txt").toStdString();
        write_file_atomic(p, "hello");
        QCOMPARE(QString::fromStdString(read_file(p)), QString("hello"));
        QString e = error_of<FileError>([&] { read_file(p, 3); });
        QVERIFY2(e.contains("f.txt") && e.contains("5 bytes"), qPrintable(e));
        e = error_of<FileError>([&] { read_file(d.path().toStdString()); });
        QVERIFY2(e.contains("is a folder"), qPrintable(e));
        e = error_of<FileError>([&] { read_file(d.filePath("missing").toStdString()); });
        QVERIFY2(e.contains("missing") && e.contains("cannot open"), qPrintable(e));
    }

    void parallel_for_runs_each_index_once_and_passes_errors_on()
    {
        std::vector<std::atomic<int>> hits(200);
        parallel_for(hits.size(), 3, [&](std::size_t i) { ++hits[i]; });
        for (const auto& h : hits) QCOMPARE(h.load(), 1);
        std::atomic<int> done{0};
        const QString e = error_of<ParameterError>([&] {
            parallel_for(100, 2, [&](std::size_t i) {
                if (i == 7) throw ParameterError("job 7 failed");
                ++done;
            });
        });
        QCOMPARE(e, QString("job 7 failed"));
        QVERIFY(done.load() < 100);
        std::atomic<int> ran{0};
        parallel_for(100, 2, [&](std::size_t) { ++ran; }, [&] { return ran.load() >= 10; });
        QVERIFY(ran.load() >= 10 && ran.load() < 100);
    }

    /// Unicode NFC from the generated tables (checked against Python's
    /// unicodedata over every code point when the tables were generated).
    void text_is_normalised_to_nfc()
    {
        QCOMPARE(to_nfc("Cafe\u0301"), std::string("Caf\u00e9"));           // e + combining acute -> é
        QCOMPARE(to_nfc("Caf\u00e9"), std::string("Caf\u00e9"));            // already NFC
        QCOMPARE(to_nfc("\u212b"), std::string("\u00c5"));                   // ANGSTROM SIGN -> Å (singleton)
        QCOMPARE(to_nfc("a\u0323\u0302"), std::string("\u1ead"));            // marks in either order ...
        QCOMPARE(to_nfc("a\u0302\u0323"), std::string("\u1ead"));            // ... compose to the same ậ
        QCOMPARE(to_nfc("\u1100\u1161\u11a8"), std::string("\uac01"));      // Hangul jamo -> 각
        QCOMPARE(to_nfc("\u0344"), std::string("\u0308\u0301"));             // an excluded composite stays decomposed
        QCOMPARE(to_nfc("\u0301a"), std::string("\u0301a"));                  // a mark before any starter is left alone
        QCOMPARE(to_nfc(""), std::string());
        QVERIFY_THROWS_EXCEPTION(ParameterError, to_nfc("bad\xff"));
        QVERIFY(!is_valid_utf8("\xc0\xaf"));         // overlong '/'
        QVERIFY(!is_valid_utf8("\xed\xa0\x80"));     // a surrogate
        QVERIFY(!is_valid_utf8("\xf4\x90\x80\x80")); // above U+10FFFF
        QVERIFY(!is_valid_utf8("\xe2\x82"));          // cut short
        QVERIFY(is_valid_utf8("\xf0\x9f\xa7\xb5"));   // 🧵
        QCOMPARE(utf8_length("\u00e9\u00e9x"), std::size_t(3));
        QVERIFY(std::string(unicode_version()).size() >= 4);
    }

    /// Names a person can tell apart: trimmed (no-break space too), NFC,
    /// limited in characters (not bytes), no control characters.
    void names_are_normalised_and_checked()
    {
        QCOMPARE(normalize_name("  silk\u00a0", "name"), std::string("silk"));
        QCOMPARE(normalize_name("\ufeffsilk\u200b", "name"), std::string("silk"));
        QCOMPARE(normalize_name("Cafe\u0301 silk", "name"), std::string("Caf\u00e9 silk"));
        std::string e150;
        for (int i = 0; i < 150; ++i) e150 += "\u00e9"; // 300 bytes, 150 characters
        QCOMPARE(normalize_name(e150, "name", 200), e150);
        std::string e201;
        for (int i = 0; i < 201; ++i) e201 += "\u00e9";
        QVERIFY(error_of<ParameterError>([&] { normalize_name(e201, "name", 200); }).contains("201 characters long"));
        QVERIFY(error_of<ParameterError>([] { normalize_name("a\tb", "name"); }).contains("control character"));
        QVERIFY(error_of<ParameterError>([] { normalize_name("a\u0085b", "name"); }).contains("control character"));
        QVERIFY(error_of<ParameterError>([] { normalize_name("evil\u202egnp.exe", "name"); }).contains("bidirectional"));
        QVERIFY(error_of<ParameterError>([] { normalize_name(" \u00a0 ", "name"); }).contains("empty"));
        QVERIFY(error_of<ParameterError>([] { normalize_name("bad\xff", "fabric name"); }).contains("fabric name 'bad\\xFF' is not valid UTF-8"));
        QVERIFY(!try_normalize_name(""));
        QCOMPARE(*try_normalize_name(" x "), std::string("x"));
    }

    /// Text from files is echoed in messages without raw control characters or
    /// broken UTF-8 (a cell "\x1b[2J" must not clear the user's terminal).
    void untrusted_text_is_echoed_printably()
    {
        QCOMPARE(printable("\x1b[2J"), std::string("\\x1B[2J"));
        QCOMPARE(printable("a\nb\tc"), std::string("a\\nb\\tc"));
        QCOMPARE(printable("caf\xe9"), std::string("caf\\xE9"));
        QCOMPARE(printable("caf\u00e9"), std::string("caf\u00e9"));
        QCOMPARE(printable("abcdef", 3), std::string("abc..."));
    }

    /// The malformed-JSON message does not carry the file's raw bytes.
    void json_errors_are_printable()
    {
        std::string e;
        try {
            parse_json("{\"name\": \"x\xff\xfe\"}", "p.json");
        } catch (const FileError& ex) {
            e = ex.what();
        }
        QVERIFY2(e.rfind("p.json: not valid JSON", 0) == 0 && is_valid_utf8(e) && e.find("\\xFF") != std::string::npos, e.c_str());
    }
};

QTEST_APPLESS_MAIN(TestCore)
#include "tst_core.moc"
