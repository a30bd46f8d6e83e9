#include "tools/iterate/rpc3_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace rigctl {

namespace {

constexpr std::size_t kBlock = 512, kRecord = 128, kKey = 32;
// Integer full scale: the largest count a channel's peak is written as. MTS
// writes 32752 (INT_FULL_SCALE), a little short of 32767.
constexpr double kFullScale = 32752.0;
// Points per frame and per group: RPC's usual 1024 and 2048.
constexpr std::size_t kPointsPerFrame = 1024, kFramesPerGroup = 2;

std::string trimmed(const char* p, std::size_t n) {
  std::string s(p, strnlen(p, n));
  const auto last = s.find_last_not_of(' ');
  return last == std::string::npos ? "" : s.substr(0, last + 1);
}

struct Header {
  std::string name;
  std::map<std::string, std::string> values;

  const std::string& text(const std::string& key) const {
    const auto it = values.find(key);
    if (it == values.end()) throw Rpc3Error(name + ": header keyword " + key + " missing");
    return it->second;
  }
  double number(const std::string& key) const {
    const std::string& v = text(key);
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(d)) throw Rpc3Error(name + ": header keyword " + key + ": '" + v + "' is not a number");
    return d;
  }
  std::size_t count(const std::string& key) const {
    const double d = number(key);
    if (d < 1 || d != std::floor(d)) throw Rpc3Error(name + ": header keyword " + key + ": '" + text(key) + "' is not a positive count");
    return static_cast<std::size_t>(d);
  }
};

std::pair<std::string, std::string> record_at(const std::string& bytes, std::size_t i) {
  const char* p = bytes.data() + i * kRecord;
  return {trimmed(p, kKey), trimmed(p + kKey, kRecord - kKey)};
}

Header parse_header(const std::string& bytes, const std::string& name) {
  Header h{name, {}};
  if (bytes.size() < kBlock) throw Rpc3Error(name + ": shorter than one 512-byte header block (" + std::to_string(bytes.size()) + " bytes)");
  const char* first[] = {"FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS"};
  for (std::size_t i = 0; i < 3; ++i) {
    const auto [k, v] = record_at(bytes, i);
    if (k != first[i]) throw Rpc3Error(name + ": header record " + std::to_string(i + 1) + " is '" + k + "', expected " + first[i]);
    h.values[k] = v;
  }
  const std::size_t blocks = h.count("NUM_HEADER_BLOCKS"), params = h.count("NUM_PARAMS");
  if (params > blocks * (kBlock / kRecord)) {
    throw Rpc3Error(name + ": NUM_PARAMS " + std::to_string(params) + " do not fit in NUM_HEADER_BLOCKS " + std::to_string(blocks));
  }
  if (bytes.size() < blocks * kBlock) throw Rpc3Error(name + ": the file ends inside its " + std::to_string(blocks) + " header blocks");
  for (std::size_t i = 3; i < params; ++i) {
    const auto [k, v] = record_at(bytes, i);
    if (k.empty()) throw Rpc3Error(name + ": header record " + std::to_string(i + 1) + " has no keyword (NUM_PARAMS says " + std::to_string(params) + ")");
    h.values[k] = v;
  }
  const std::string& format = h.text("FORMAT");
  if (format != "BINARY" && format != "BINARY_IEEE_LITTLE_END") {
    throw Rpc3Error(name + ": FORMAT " + format + " is not read (only BINARY and BINARY_IEEE_LITTLE_END)");
  }
  return h;
}

template <typename T>
T little_endian_at(const std::string& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);  // the build's targets are little-endian (x86-64, arm64)
  return v;
}

}  // namespace

const std::vector<double>& Rpc3File::channel(const std::string& n, const std::string& file) const {
  std::string known;
  for (const auto& c : channels) {
    if (c.name == n) return c.values;
    known += (known.empty() ? "" : ", ") + c.name;
  }
  throw Rpc3Error(file + ": no channel '" + n + "' (channels: " + known + ")");
}

bool is_rpc3_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".rsp" || ext == ".drv" || ext == ".tim" || ext == ".rpc";
}

std::string rpc3_time_type_for(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".drv" ? "DRIVE" : "RESPONSE";
}

Rpc3File parse_rpc3(const std::string& bytes, const std::string& name) {
  const Header h = parse_header(bytes, name);
  if (h.text("FILE_TYPE") != "TIME_HISTORY") throw Rpc3Error(name + ": FILE_TYPE " + h.text("FILE_TYPE") + " is not a TIME_HISTORY");
  const std::string& type = h.text("DATA_TYPE");
  const bool integers = type == "SHORT_INTEGER";
  if (!integers && type != "FLOATING_POINT") throw Rpc3Error(name + ": DATA_TYPE " + type + " is not SHORT_INTEGER or FLOATING_POINT");
  Rpc3File f;
  f.time_type = h.values.count("TIME_TYPE") ? h.text("TIME_TYPE") : "";
  f.period_s = h.number("DELTA_T");
  if (!(f.period_s > 0.0)) throw Rpc3Error(name + ": DELTA_T must be positive");
  const std::size_t channels = h.count("CHANNELS"), per_frame = h.count("PTS_PER_FRAME"),
                    per_group = h.count("PTS_PER_GROUP"), frames = h.count("FRAMES");
  const std::size_t points = frames * per_frame, groups = (points + per_group - 1) / per_group;
  const std::size_t width = integers ? 2 : 4, data_at = h.count("NUM_HEADER_BLOCKS") * kBlock;
  if (bytes.size() < data_at + groups * per_group * channels * width) {
    throw Rpc3Error(name + ": the data hold fewer than the header's " + std::to_string(frames) + " frames of " +
                    std::to_string(per_frame) + " points on " + std::to_string(channels) + " channels");
  }
  for (std::size_t c = 0; c < channels; ++c) {
    const std::string n = std::to_string(c + 1);
    Rpc3Channel ch{h.text("DESC.CHAN_" + n), h.values.count("UNITS.CHAN_" + n) ? h.text("UNITS.CHAN_" + n) : "", {}};
    const double scale = integers ? h.number("SCALE.CHAN_" + n) : 1.0;
    ch.values.reserve(points);
    for (std::size_t i = 0; i < points; ++i) {
      const std::size_t g = i / per_group, k = i % per_group;
      const std::size_t at = data_at + ((g * channels + c) * per_group + k) * width;
      ch.values.push_back(integers ? scale * little_endian_at<int16_t>(bytes, at) : little_endian_at<float>(bytes, at));
    }
    f.channels.push_back(std::move(ch));
  }
  return f;
}

Rpc3File read_rpc3_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Rpc3Error("cannot read " + path);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  return parse_rpc3(bytes, path);
}

namespace {

void put_record(std::string& out, const std::string& key, const std::string& value) {
  std::string r(kRecord, '\0');
  r.replace(0, std::min(key.size(), kKey), key.substr(0, kKey));
  r.replace(kKey, std::min(value.size(), kRecord - kKey), value.substr(0, kRecord - kKey));
  out += r;
}

std::string sci(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9E", v);
  return b;
}

}  // namespace

std::string rpc3_bytes(const Rpc3File& f, Rpc3DataType type) {
  if (f.channels.empty()) throw Rpc3Error("RPC III: no channels to write");
  const std::size_t points = f.channels.front().values.size();
  for (const auto& c : f.channels) {
    if (c.values.size() != points || points == 0) throw Rpc3Error("RPC III: channel " + c.name + " differs in length or is empty");
  }
  const bool integers = type == Rpc3DataType::kShortInteger;
  const std::size_t frames = (points + kPointsPerFrame - 1) / kPointsPerFrame;
  const std::size_t per_group = kPointsPerFrame * kFramesPerGroup;
  std::vector<std::pair<std::string, std::string>> rec{
      {"FILE_TYPE", "TIME_HISTORY"}, {"TIME_TYPE", f.time_type}, {"DELTA_T", sci(f.period_s)},
      {"CHANNELS", std::to_string(f.channels.size())}, {"DATA_TYPE", integers ? "SHORT_INTEGER" : "FLOATING_POINT"},
      {"PTS_PER_FRAME", std::to_string(kPointsPerFrame)}, {"PTS_PER_GROUP", std::to_string(per_group)},
      {"FRAMES", std::to_string(frames)}, {"INT_FULL_SCALE", std::to_string(static_cast<int>(kFullScale))},
      {"REPEATS", "1"}, {"OPERATION", "rigctl"}};
  std::vector<double> scales;
  for (std::size_t c = 0; c < f.channels.size(); ++c) {
    const auto& ch = f.channels[c];
    double peak = 0.0;
    for (double v : ch.values) peak = std::max(peak, std::abs(v));
    scales.push_back(peak > 0.0 ? peak / kFullScale : 1.0);
    const std::string n = std::to_string(c + 1);
    rec.insert(rec.end(), {{"DESC.CHAN_" + n, ch.name}, {"UNITS.CHAN_" + n, ch.unit}, {"SCALE.CHAN_" + n, sci(integers ? scales.back() : 1.0)},
                           {"LOWER_LIMIT.CHAN_" + n, sci(-peak)}, {"UPPER_LIMIT.CHAN_" + n, sci(peak)}});
  }
  const std::size_t params = rec.size() + 3, blocks = (params + 3) / 4;
  std::string out;
  put_record(out, "FORMAT", "BINARY_IEEE_LITTLE_END");
  put_record(out, "NUM_HEADER_BLOCKS", std::to_string(blocks));
  put_record(out, "NUM_PARAMS", std::to_string(params));
  for (const auto& [k, v] : rec) put_record(out, k, v);
  out.resize(blocks * kBlock, '\0');
  const std::size_t groups = (frames * kPointsPerFrame + per_group - 1) / per_group;
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t c = 0; c < f.channels.size(); ++c) {
      const auto& v = f.channels[c].values;
      for (std::size_t k = 0; k < per_group; ++k) {
        const double x = v[std::min(g * per_group + k, points - 1)];  // padded with the last value
        if (integers) {
          const auto q = static_cast<int16_t>(std::lround(x / scales[c]));
          out.append(reinterpret_cast<const char*>(&q), sizeof q);
        } else {
          const auto q = static_cast<float>(x);
          out.append(reinterpret_cast<const char*>(&q), sizeof q);
        }
      }
    }
  }
  return out;
}

void write_rpc3_file(const Rpc3File& f, const std::string& path, Rpc3DataType type) {
  const std::string bytes = rpc3_bytes(f, type);
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw Rpc3Error("cannot write " + path);
}

}  // namespace rigctl
