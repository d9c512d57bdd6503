#pragma once
// Thin RAII helpers over the SQLite C API for the fabric library: a prepared
// statement, a transaction that rolls back unless committed, and errors that
// carry SQLite's result code (so callers branch on the code, not on message
// text) and name the library file.
#include "engine/core/error.hpp"

#include <cstdint>
#include <optional>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace drape::library::sql {

/// A database error: a FileError naming the library file, with SQLite's
/// extended result code.
class DatabaseError : public FileError {
public:
    DatabaseError(const std::string& message, int code) : FileError(message), m_code(code) {}
    int code() const { return m_code; }                 ///< extended result code
    int primary_code() const { return m_code & 0xff; }  ///< SQLITE_FULL, SQLITE_NOTADB, ...
private:
    int m_code;
};

/// A prepared statement. Every error becomes a DatabaseError naming `path`.
class Stmt {
public:
    Stmt(sqlite3* db, const std::string& path, const std::string& sql);
    ~Stmt();
    Stmt(const Stmt&) = delete;
    Stmt& operator=(const Stmt&) = delete;

    Stmt& bind(int i, const std::string& v);
    Stmt& bind(int i, double v);
    Stmt& bind(int i, std::int64_t v);
    Stmt& bind(int i, const std::optional<double>& v); ///< NULL when empty
    /// True while there is a row.
    bool step();
    void run(); ///< steps to the end
    std::string text(int c) const;
    double real(int c) const;
    std::int64_t integer(int c) const;
    std::optional<double> opt_real(int c) const;

private:
    void check(int rc, const char* what);
    [[noreturn]] void fail(const char* what);
    sqlite3* m_db;
    const std::string& m_path;
    sqlite3_stmt* m_s = nullptr;
};

/// Runs SQL text (several statements allowed). Throws DatabaseError.
void exec(sqlite3* db, const std::string& path, const std::string& sql);
/// An integer PRAGMA's value (0 when it returns no row).
std::int64_t pragma_int(sqlite3* db, const std::string& path, const std::string& pragma);

/// One transaction: rolled back unless commit() ran, so an exception in the
/// middle of a write leaves the database as it was.
class Transaction {
public:
    /// `write`: BEGIN IMMEDIATE (takes the write lock up front, so two writers
    /// queue on the busy timeout instead of failing on lock upgrade).
    Transaction(sqlite3* db, const std::string& path, bool write);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    void commit();

private:
    sqlite3* m_db;
    const std::string& m_path;
    bool m_done = false;
};

} // namespace drape::library::sql
