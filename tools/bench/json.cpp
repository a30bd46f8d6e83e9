#include "tools/bench/json.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "tools/common/json_text.hpp"

namespace rigctl {

Json& Json::operator[](const std::string& key) {
  if (type_ == Type::kNull) type_ = Type::kObject;
  if (type_ != Type::kObject) throw std::logic_error("json: [\"" + key + "\"] on a value that is not an object");
  for (auto& [k, v] : members_) {
    if (k == key) return v;
  }
  members_.emplace_back(key, Json());
  return members_.back().second;
}

const Json* Json::find(const std::string& key) const {
  if (type_ != Type::kObject) return nullptr;
  for (const auto& [k, v] : members_) {
    if (k == key) return &v;
  }
  return nullptr;
}

void Json::push_back(Json value) {
  if (type_ == Type::kNull) type_ = Type::kArray;
  if (type_ != Type::kArray) throw std::logic_error("json: push_back on a value that is not an array");
  items_.push_back(std::move(value));
}

namespace {

// One string formatter for every JSON the program writes (tools/json_text).
void escape_to(std::string& out, const std::string& s) { out += json_string(s); }

void newline(std::string& out, int indent, int depth) {
  if (indent < 0) return;
  out += '\n';
  out.append(static_cast<std::size_t>(indent * depth), ' ');
}

}  // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
  switch (type_) {
    case Type::kNull: out += "null"; return;
    case Type::kBool: out += bool_ ? "true" : "false"; return;
    case Type::kNumber: {
      if (!std::isfinite(number_)) {
        out += "null";
        return;
      }
      char buf[32];
      if (number_ == std::floor(number_) && std::abs(number_) < 1e15) {
        std::snprintf(buf, sizeof buf, "%.0f", number_);
      } else {
        std::snprintf(buf, sizeof buf, "%.6g", number_);
      }
      out += buf;
      return;
    }
    case Type::kString: escape_to(out, string_); return;
    case Type::kArray: {
      out += '[';
      // Arrays of numbers stay on one line: they are series, not records.
      bool flat = true;
      for (const auto& v : items_) flat = flat && (v.type_ != Type::kArray && v.type_ != Type::kObject);
      for (std::size_t i = 0; i < items_.size(); ++i) {
        if (i > 0) out += flat || indent < 0 ? ", " : ",";
        if (!flat) newline(out, indent, depth + 1);
        items_[i].dump_to(out, indent, depth + 1);
      }
      if (!flat && !items_.empty()) newline(out, indent, depth);
      out += ']';
      return;
    }
    case Type::kObject: {
      out += '{';
      for (std::size_t i = 0; i < members_.size(); ++i) {
        if (i > 0) out += indent < 0 ? ", " : ",";
        newline(out, indent, depth + 1);
        escape_to(out, members_[i].first);
        out += ": ";
        members_[i].second.dump_to(out, indent, depth + 1);
      }
      if (!members_.empty()) newline(out, indent, depth);
      out += '}';
      return;
    }
  }
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  if (indent >= 0) out += '\n';
  return out;
}

namespace {

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}

  Json document() {
    Json v = value();
    skip();
    if (pos_ != s_.size()) fail("trailing characters");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("json: " + what + " at offset " + std::to_string(pos_));
  }
  void skip() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\n' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
  }
  bool take(char c) {
    skip();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!take(c)) fail(std::string("expected '") + c + "'");
  }
  bool word(const char* w) {
    const std::string ws(w);
    if (s_.compare(pos_, ws.size(), ws) == 0) {
      pos_ += ws.size();
      return true;
    }
    return false;
  }

  std::string string_body() {
    std::string out;
    while (pos_ < s_.size() && s_[pos_] != '"') {
      char c = s_[pos_++];
      if (c == '\\') {
        if (pos_ >= s_.size()) fail("bad escape");
        const char e = s_[pos_++];
        switch (e) {
          case 'n': c = '\n'; break;
          case 't': c = '\t'; break;
          case 'r': c = '\r'; break;
          case 'b': c = '\b'; break;
          case 'f': c = '\f'; break;
          case 'u': {
            if (pos_ + 4 > s_.size()) fail("bad \\u escape");
            const unsigned long code = std::stoul(s_.substr(pos_, 4), nullptr, 16);
            pos_ += 4;
            c = code < 0x80 ? static_cast<char>(code) : '?';
            break;
          }
          default: c = e;
        }
      }
      out += c;
    }
    if (pos_ >= s_.size()) fail("unterminated string");
    ++pos_;
    return out;
  }

  Json value() {
    skip();
    if (pos_ >= s_.size()) fail("unexpected end");
    const char c = s_[pos_];
    if (c == '{') {
      ++pos_;
      Json o = Json::object();
      if (take('}')) return o;
      do {
        skip();
        if (pos_ >= s_.size() || s_[pos_] != '"') fail("expected a key");
        ++pos_;
        const std::string key = string_body();
        expect(':');
        o[key] = value();
      } while (take(','));
      expect('}');
      return o;
    }
    if (c == '[') {
      ++pos_;
      Json a = Json::array();
      if (take(']')) return a;
      do {
        a.push_back(value());
      } while (take(','));
      expect(']');
      return a;
    }
    if (c == '"') {
      ++pos_;
      return Json(string_body());
    }
    if (word("true")) return Json(true);
    if (word("false")) return Json(false);
    if (word("null")) return Json();
    std::size_t used = 0;
    double d = 0.0;
    try {
      d = std::stod(s_.substr(pos_, 40), &used);
    } catch (const std::exception&) {
      fail("bad value");
    }
    pos_ += used;
    return Json(d);
  }

  const std::string& s_;
  std::size_t pos_ = 0;
};

}  // namespace

Json Json::parse(const std::string& text) { return Parser(text).document(); }

}  // namespace rigctl
