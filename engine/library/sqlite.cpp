#include "engine/library/sqlite.hpp"

#include <sqlite3.h>

namespace drape::library::sql {

namespace {
std::string full_disk_note(int code)
{
    return (code & 0xff) == SQLITE_FULL ? "; the write was rolled back and the library is unchanged" : "";
}
} // namespace

Stmt::Stmt(sqlite3* db, const std::string& path, const std::string& sql) : m_db(db), m_path(path)
{
    if (sqlite3_prepare_v2(db, sql.c_str(), static_cast<int>(sql.size()), &m_s, nullptr) != SQLITE_OK) fail("prepare");
}

Stmt::~Stmt() { sqlite3_finalize(m_s); }

Stmt& Stmt::bind(int i, const std::string& v)
{
    check(sqlite3_bind_text(m_s, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT), "bind");
    return *this;
}

Stmt& Stmt::bind(int i, double v)
{
    check(sqlite3_bind_double(m_s, i, v), "bind");
    return *this;
}

Stmt& Stmt::bind(int i, std::int64_t v)
{
    check(sqlite3_bind_int64(m_s, i, v), "bind");
    return *this;
}

Stmt& Stmt::bind(int i, const std::optional<double>& v)
{
    if (v) return bind(i, *v);
    check(sqlite3_bind_null(m_s, i), "bind");
    return *this;
}

bool Stmt::step()
{
    const int rc = sqlite3_step(m_s);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("step");
}

void Stmt::run()
{
    while (step()) {
    }
}

std::string Stmt::text(int c) const
{
    const auto* t = sqlite3_column_text(m_s, c);
    return t ? std::string(reinterpret_cast<const char*>(t), static_cast<std::size_t>(sqlite3_column_bytes(m_s, c))) : std::string();
}

double Stmt::real(int c) const { return sqlite3_column_double(m_s, c); }
std::int64_t Stmt::integer(int c) const { return sqlite3_column_int64(m_s, c); }

std::optional<double> Stmt::opt_real(int c) const
{
    if (sqlite3_column_type(m_s, c) == SQLITE_NULL) return std::nullopt;
    return real(c);
}

void Stmt::check(int rc, const char* what)
{
    if (rc != SQLITE_OK) fail(what);
}

void Stmt::fail(const char* what)
{
    const int code = sqlite3_extended_errcode(m_db);
    throw DatabaseError(m_path + ": database error (" + what + "): " + sqlite3_errmsg(m_db) + full_disk_note(code), code);
}

void exec(sqlite3* db, const std::string& path, const std::string& sql)
{
    char* err = nullptr;
    if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
        const std::string m = err ? err : sqlite3_errmsg(db);
        sqlite3_free(err);
        const int code = sqlite3_extended_errcode(db);
        throw DatabaseError(path + ": database error: " + m + " (in: " + sql.substr(0, 60) + ")" + full_disk_note(code), code);
    }
}

std::int64_t pragma_int(sqlite3* db, const std::string& path, const std::string& pragma)
{
    Stmt s(db, path, "PRAGMA " + pragma);
    return s.step() ? s.integer(0) : 0;
}

Transaction::Transaction(sqlite3* db, const std::string& path, bool write) : m_db(db), m_path(path)
{
    exec(db, path, write ? "BEGIN IMMEDIATE" : "BEGIN");
}

Transaction::~Transaction()
{
    if (!m_done) sqlite3_exec(m_db, "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit()
{
    exec(m_db, m_path, "COMMIT");
    m_done = true;
}

} // namespace drape::library::sql
