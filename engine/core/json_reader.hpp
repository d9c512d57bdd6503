#pragma once
// Reading fields out of a JSON document with errors that name the file, the
// field (as a dotted path, "configuration.specimen_diameter_D1_mm") and the
// offending value: one reader for meta.json, presets and library documents.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace drape {

/// A short description of a JSON value for messages: its type and (cut) text.
std::string describe_json(const nlohmann::json& v);

class JsonReader {
public:
    /// `where` names the document in every message (usually its path).
    explicit JsonReader(std::string where) : m_where(std::move(where)) {}

    /// Throws FileError "<where>: field '<field>' <what>".
    [[noreturn]] void fail(const std::string& field, const std::string& what) const;

    /// The value at a dotted path, or nullptr when any step is missing.
    static const nlohmann::json* find(const nlohmann::json& root, const std::string& path);
    const nlohmann::json& need(const nlohmann::json& root, const std::string& path) const;

    /// A finite number.
    double number(const nlohmann::json& root, const std::string& path) const;
    /// A finite number in [lo, hi] (the message gives the range and the unit).
    double number_in(const nlohmann::json& root, const std::string& path, double lo, double hi,
                     const std::string& unit = "") const;
    double positive(const nlohmann::json& root, const std::string& path) const;
    std::optional<double> optional_number(const nlohmann::json& root, const std::string& path) const;
    /// An integral number in [min, max].
    int integer(const nlohmann::json& root, const std::string& path, int min, int max = 1000000) const;
    bool boolean(const nlohmann::json& root, const std::string& path) const;
    std::string string(const nlohmann::json& root, const std::string& path) const;
    /// An array of finite numbers (of `n_expected` entries unless 0).
    std::vector<double> numbers(const nlohmann::json& root, const std::string& path, std::size_t n_expected) const;

    const std::string& where() const { return m_where; }

private:
    std::string m_where;
};

} // namespace drape
