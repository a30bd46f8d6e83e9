// A thin RAII wrapper over Debian's libsqlite3: one connection, prepared
// statements with bound parameters (never text pasted into SQL), and errors
// that name the database file and what was being done.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace rigctl::catalog {

class CatalogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Statement;

class Database {
 public:
  // Opens (creates when missing) the file, with foreign keys on, WAL
  // journalling (a reader never blocks the run's writer) and a busy timeout
  // (two rigctl processes on one file wait for each other instead of failing).
  explicit Database(const std::string& path);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  void exec(const std::string& sql);  // statements without parameters or results
  Statement prepare(const std::string& sql);
  int64_t last_insert_id() const;
  int user_version();
  void set_user_version(int version);
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& doing) const;

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

// One transaction: committed by commit(), rolled back when left otherwise
// (an exception), so the file never holds half an entry.
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  void commit();

 private:
  Database& db_;
  bool done_ = false;
};

class Statement {
 public:
  Statement(Database& db, sqlite3_stmt* stmt, std::string sql);
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters by position, 1-based as SQLite counts them.
  Statement& bind(int index, const std::string& value);
  Statement& bind(int index, const char* value) { return bind(index, std::string(value)); }
  Statement& bind(int index, double value);
  Statement& bind(int index, int64_t value);
  Statement& bind(int index, int value) { return bind(index, static_cast<int64_t>(value)); }
  Statement& bind_null(int index);
  Statement& bind(int index, const std::optional<double>& value) {
    return value ? bind(index, *value) : bind_null(index);
  }

  bool step();  // true: a row is ready; false: done
  void run();   // step to the end (INSERT, UPDATE)
  void reset();

  bool is_null(int column) const;
  std::string text(int column) const;
  double real(int column) const;
  int64_t integer(int column) const;
  std::optional<double> maybe_real(int column) const;

 private:
  Database* db_;
  sqlite3_stmt* stmt_;
  std::string sql_;
};

}  // namespace rigctl::catalog
