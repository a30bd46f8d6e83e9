#include "tools/catalog/catalog.hpp"

#include <cstdlib>

#include "tools/catalog/schema.hpp"

namespace rigctl::catalog {

namespace {

constexpr const char* kRunColumns =
    "id, rig_kind, rig_name, config_path, config_sha256, revision, start_utc, duration_s, profile, end_reason, "
    "end_detail, trips, samples, log_path, log_bytes, log_sha256, entered_by, pid, host";

// Binds the run's fields as ?1..?18 in kRunColumns' order after id.
void bind_run(Statement& s, const RunEntry& r) {
  s.bind(1, r.rig_kind).bind(2, r.rig_name).bind(3, r.config_path).bind(4, r.config_sha256).bind(5, r.revision);
  s.bind(6, r.start_utc).bind(7, r.duration_s).bind(8, r.profile).bind(9, std::string(to_string(r.end_reason)));
  s.bind(10, r.end_detail).bind(11, r.trips).bind(12, r.samples).bind(13, r.log_path).bind(14, r.log_bytes);
  s.bind(15, r.log_sha256).bind(16, std::string(to_string(r.entered_by))).bind(17, r.pid).bind(18, r.host);
}

// A name the catalog wrote itself; an unknown one (a newer rigctl's) reads as unknown.
template <typename Kind>
Kind read_kind(const std::string& text, Kind fallback) {
  const auto k = kind_from_string<Kind>(text);
  return k ? *k : fallback;
}

RunEntry read_run(const Statement& s) {
  RunEntry r;
  r.id = s.integer(0);
  r.rig_kind = s.text(1);
  r.rig_name = s.text(2);
  r.config_path = s.text(3);
  r.config_sha256 = s.text(4);
  r.revision = s.text(5);
  r.start_utc = s.text(6);
  r.duration_s = s.real(7);
  r.profile = s.text(8);
  r.end_reason = read_kind(s.text(9), EndReason::kUnknown);
  r.end_detail = s.text(10);
  r.trips = s.integer(11);
  r.samples = s.integer(12);
  r.log_path = s.text(13);
  r.log_bytes = s.integer(14);
  r.log_sha256 = s.text(15);
  r.entered_by = read_kind(s.text(16), EnteredBy::kAdd);
  r.pid = s.integer(17);
  r.host = s.text(18);
  return r;
}

}  // namespace

ChannelCondition parse_channel_condition(const std::string& text) {
  const auto op = text.find_first_of("<>");
  const auto dot = text.rfind('.', op);
  if (op == std::string::npos || dot == std::string::npos || dot == 0) {
    throw CatalogError("--where '" + text + "': expected CHANNEL.STATISTIC<VALUE or >VALUE, e.g. x_r.max>0.05");
  }
  ChannelCondition c;
  c.channel = text.substr(0, dot);
  const auto stat = kind_from_string<Statistic>(text.substr(dot + 1, op - dot - 1));
  if (!stat) {
    throw CatalogError("--where '" + text + "': " + unknown_kind_message<Statistic>(text.substr(dot + 1, op - dot - 1)));
  }
  c.statistic = *stat;
  c.op = text[op] == '<' ? ChannelCondition::Op::kLess : ChannelCondition::Op::kGreater;
  const std::string number = text.substr(op + 1);
  char* end = nullptr;
  c.value = std::strtod(number.c_str(), &end);
  if (number.empty() || end == nullptr || *end != '\0') throw CatalogError("--where '" + text + "': '" + number + "' is not a number");
  return c;
}

Catalog::Catalog(const std::string& path) : db_(path) { migrate(db_); }

int64_t Catalog::begin_run(const RunEntry& run) {
  RunEntry r = run;
  r.end_reason = EndReason::kRunning;
  return add_run(r);
}

int64_t Catalog::add_run(const RunEntry& run) {
  Transaction tx(db_);
  {
    auto existing = db_.prepare("SELECT id, start_utc FROM runs WHERE log_path = ?1");
    existing.bind(1, run.log_path);
    if (existing.step()) {
      throw CatalogError("catalog '" + db_.path() + "': the log '" + run.log_path + "' is already entered as run " +
                         std::to_string(existing.integer(0)) + " (started " + existing.text(1) + ")");
    }
  }
  auto s = db_.prepare(
      "INSERT INTO runs (rig_kind, rig_name, config_path, config_sha256, revision, start_utc, duration_s, profile, "
      "end_reason, end_detail, trips, samples, log_path, log_bytes, log_sha256, entered_by, pid, host) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18)");
  bind_run(s, run);
  s.run();
  const int64_t id = db_.last_insert_id();
  write_channels(id, run.channels);
  tx.commit();
  return id;
}

void Catalog::finish_run(int64_t id, const RunEntry& run) {
  Transaction tx(db_);
  auto s = db_.prepare(
      "UPDATE runs SET rig_kind = ?1, rig_name = ?2, config_path = ?3, config_sha256 = ?4, revision = ?5, "
      "start_utc = ?6, duration_s = ?7, profile = ?8, end_reason = ?9, end_detail = ?10, trips = ?11, samples = ?12, "
      "log_path = ?13, log_bytes = ?14, log_sha256 = ?15, entered_by = ?16, pid = ?17, host = ?18 WHERE id = ?19");
  bind_run(s, run);
  s.bind(19, id);
  s.run();
  auto del = db_.prepare("DELETE FROM channel_stats WHERE run_id = ?1");
  del.bind(1, id).run();
  write_channels(id, run.channels);
  tx.commit();
}

void Catalog::write_channels(int64_t id, const std::vector<ChannelStats>& channels) {
  auto s = db_.prepare(
      "INSERT INTO channel_stats (run_id, channel, unit, count, min, max, mean, std, rms) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
  for (const auto& c : channels) {
    s.reset();
    s.bind(1, id).bind(2, c.channel).bind(3, c.unit).bind(4, c.count);
    s.bind(5, c.min).bind(6, c.max).bind(7, c.mean).bind(8, c.std).bind(9, c.rms);
    s.run();
  }
}

std::vector<ChannelStats> Catalog::read_channels(int64_t id) {
  auto s = db_.prepare(
      "SELECT channel, unit, count, min, max, mean, std, rms FROM channel_stats WHERE run_id = ?1 ORDER BY rowid");
  s.bind(1, id);
  std::vector<ChannelStats> out;
  while (s.step()) {
    out.push_back({s.text(0), s.text(1), s.integer(2), s.real(3), s.real(4), s.real(5), s.real(6), s.real(7)});
  }
  return out;
}

std::optional<RunEntry> Catalog::run(int64_t id) {
  auto s = db_.prepare(std::string("SELECT ") + kRunColumns + " FROM runs WHERE id = ?1");
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  RunEntry r = read_run(s);
  r.channels = read_channels(id);
  return r;
}

std::optional<RunEntry> Catalog::run_by_log(const std::string& log_path) {
  auto s = db_.prepare("SELECT id FROM runs WHERE log_path = ?1");
  s.bind(1, log_path);
  if (!s.step()) return std::nullopt;
  return run(s.integer(0));
}

std::optional<RunEntry> Catalog::run_by_log_name(const std::string& file_name) {
  // Matched in C++, not with LIKE: a name may hold % or _.
  auto s = db_.prepare("SELECT id, log_path FROM runs");
  std::optional<int64_t> found;
  while (s.step()) {
    const std::string p = s.text(1);
    const auto slash = p.rfind('/');
    if ((slash == std::string::npos ? p : p.substr(slash + 1)) != file_name) continue;
    if (found) return std::nullopt;  // ambiguous
    found = s.integer(0);
  }
  if (!found) return std::nullopt;
  return run(*found);
}

std::vector<RunEntry> Catalog::runs(const RunFilter& f) {
  std::string sql = std::string("SELECT ") + kRunColumns + " FROM runs r WHERE 1";
  int n = 0;
  if (!f.rig.empty()) {
    const std::string p = "?" + std::to_string(++n);
    sql += " AND (rig_name = " + p + " OR rig_kind = " + p + ")";
  }
  if (!f.since.empty()) sql += " AND start_utc >= ?" + std::to_string(++n);
  if (!f.until.empty()) sql += " AND start_utc < ?" + std::to_string(++n);
  if (f.end_reason) sql += " AND end_reason = ?" + std::to_string(++n);
  for (const auto& c : f.channels) {
    // The statistic's column comes from the enum's own names, never from the user's text.
    const std::string channel = "?" + std::to_string(++n);
    const std::string value = "?" + std::to_string(++n);
    sql += " AND EXISTS (SELECT 1 FROM channel_stats c WHERE c.run_id = r.id AND c.channel = " + channel + " AND c." +
           std::string(to_string(c.statistic)) + (c.op == ChannelCondition::Op::kLess ? " < " : " > ") + value + ")";
  }
  sql += " ORDER BY start_utc, id";
  auto s = db_.prepare(sql);
  int i = 0;
  if (!f.rig.empty()) s.bind(++i, f.rig);
  if (!f.since.empty()) s.bind(++i, f.since);
  if (!f.until.empty()) s.bind(++i, f.until);
  if (f.end_reason) s.bind(++i, std::string(to_string(*f.end_reason)));
  for (const auto& c : f.channels) {
    s.bind(++i, c.channel);
    s.bind(++i, c.value);
  }
  std::vector<RunEntry> out;
  while (s.step()) out.push_back(read_run(s));
  return out;
}

}  // namespace rigctl::catalog
