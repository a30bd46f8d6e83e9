// A small JSON value for `rigctl bench --json`: objects keep their keys in
// insertion order (the file reads in the order the bench ran), numbers are
// doubles (NaN and infinities are written as null, which JSON has no other
// way to say), and parse() reads back what dump() writes, for the tests.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rigctl {

class Json {
 public:
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };

  Json() = default;
  Json(std::nullptr_t) {}
  Json(bool b) : type_(Type::kBool), bool_(b) {}
  Json(double d) : type_(Type::kNumber), number_(d) {}
  Json(int i) : type_(Type::kNumber), number_(i) {}
  Json(int64_t i) : type_(Type::kNumber), number_(static_cast<double>(i)) {}
  Json(uint64_t i) : type_(Type::kNumber), number_(static_cast<double>(i)) {}
  Json(const char* s) : type_(Type::kString), string_(s) {}
  Json(std::string s) : type_(Type::kString), string_(std::move(s)) {}

  static Json object() {
    Json j;
    j.type_ = Type::kObject;
    return j;
  }
  static Json array() {
    Json j;
    j.type_ = Type::kArray;
    return j;
  }

  Type type() const { return type_; }
  bool is_null() const { return type_ == Type::kNull; }
  bool is_object() const { return type_ == Type::kObject; }
  bool is_array() const { return type_ == Type::kArray; }
  bool is_number() const { return type_ == Type::kNumber; }
  bool is_string() const { return type_ == Type::kString; }

  // Object access: inserts a null member when absent (a null value becomes an object).
  Json& operator[](const std::string& key);
  // Read-only lookup: nullptr when absent or not an object.
  const Json* find(const std::string& key) const;
  bool contains(const std::string& key) const { return find(key) != nullptr; }
  const std::vector<std::pair<std::string, Json>>& members() const { return members_; }

  // Array access (a null value becomes an array).
  void push_back(Json value);
  const std::vector<Json>& items() const { return items_; }
  std::size_t size() const { return type_ == Type::kArray ? items_.size() : members_.size(); }

  double number() const { return number_; }
  bool boolean() const { return bool_; }
  const std::string& string() const { return string_; }

  // indent < 0: one line.
  std::string dump(int indent = 2) const;
  // Throws std::runtime_error with the offset of the first error.
  static Json parse(const std::string& text);

 private:
  void dump_to(std::string& out, int indent, int depth) const;

  Type type_ = Type::kNull;
  bool bool_ = false;
  double number_ = 0.0;
  std::string string_;
  std::vector<Json> items_;
  std::vector<std::pair<std::string, Json>> members_;
};

}  // namespace rigctl
