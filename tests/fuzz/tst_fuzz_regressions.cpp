// Every input a fuzzer found (fuzz/regressions/TARGET/*, see docs/reliability.md)
// replayed through the target's own code: it must end in a drape::Error or a
// result that keeps the target's invariants (a violation aborts the test).
#include <QTest>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#define DECLARE(name) int drape_fuzz_##name(const std::uint8_t* data, std::size_t size);
DECLARE(names)
DECLARE(meta)
DECLARE(contours)
DECLARE(preset)
DECLARE(library)
DECLARE(mesh)
DECLARE(image)
#undef DECLARE

namespace fs = std::filesystem;

class TestFuzzRegressions : public QObject {
    Q_OBJECT

    static int replay(const char* target, int (*fn)(const std::uint8_t*, std::size_t))
    {
        const fs::path dir = fs::path(DRAPE_SOURCE_DIR) / "fuzz" / "regressions" / target;
        int n = 0;
        std::error_code ec;
        if (!fs::is_directory(dir, ec)) return 0;
        for (const auto& e : fs::directory_iterator(dir)) {
            if (!e.is_regular_file() || e.path().filename() == "README.md") continue;
            std::ifstream in(e.path(), std::ios::binary);
            const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
            qInfo("%s: %s (%zu bytes)", target, e.path().filename().c_str(), bytes.size());
            fn(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
            ++n;
        }
        return n;
    }

private slots:
    void names() { replay("names", drape_fuzz_names); }
    void meta() { replay("meta", drape_fuzz_meta); }
    void contours() { replay("contours", drape_fuzz_contours); }
    void preset() { replay("preset", drape_fuzz_preset); }
    void library() { replay("library", drape_fuzz_library); }
    void mesh() { replay("mesh", drape_fuzz_mesh); }
    void image() { replay("image", drape_fuzz_image); }
};

QTEST_GUILESS_MAIN(TestFuzzRegressions)
#include "tst_fuzz_regressions.moc"
