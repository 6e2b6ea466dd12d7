// One SQLite statement, prepared or borrowed from the store's cache, with typed binds and reads:
// the store's files share it (internal to server/).
#pragma once

#include <sqlite3.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "server/store.hpp"

namespace corridor::server {

class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : owned_(true) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) {
      throw StoreError(std::string("cannot prepare statement: ") + sqlite3_errmsg(db));
    }
  }
  // Borrows a prepared statement from the store's cache and resets it for the next user.
  explicit Statement(sqlite3_stmt* cached) : stmt_(cached), owned_(false) {}
  ~Statement() {
    if (owned_) {
      sqlite3_finalize(stmt_);
    } else {
      sqlite3_reset(stmt_);
      sqlite3_clear_bindings(stmt_);
    }
  }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& bind(int i, double v) { return check(sqlite3_bind_double(stmt_, i, v)); }
  Statement& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(stmt_, i, v)); }
  Statement& bind(int i, const std::string& v) {
    return check(sqlite3_bind_text(stmt_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  Statement& bind(int i, std::optional<double> v) {
    return v && std::isfinite(*v) ? bind(i, *v) : check(sqlite3_bind_null(stmt_, i));
  }
  // True while rows come; throws on error.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw StoreError(std::string("database write failed: ") + sqlite3_errmsg(sqlite3_db_handle(stmt_)));
  }
  [[nodiscard]] double real(int col) const { return sqlite3_column_double(stmt_, col); }
  [[nodiscard]] std::int64_t integer(int col) const { return sqlite3_column_int64(stmt_, col); }
  [[nodiscard]] bool null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  [[nodiscard]] std::optional<double> optional_real(int col) const {
    return null(col) ? std::nullopt : std::optional<double>(real(col));
  }
  [[nodiscard]] std::string text(int col) const {
    const auto* p = sqlite3_column_text(stmt_, col);
    return p == nullptr ? std::string{} : std::string(reinterpret_cast<const char*>(p));
  }

 private:
  Statement& check(int rc) {
    if (rc != SQLITE_OK) throw StoreError("cannot bind statement parameter");
    return *this;
  }
  sqlite3_stmt* stmt_ = nullptr;
  bool owned_;
};


}  // namespace corridor::server
