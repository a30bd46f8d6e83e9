#include "foxglove/mcap/mcap_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <unistd.h>

#include "foxglove/mcap/records.hpp"

namespace rigctl::mcap {

McapWriter::McapWriter(const std::string& path, const std::string& profile, const std::string& library,
                       std::size_t chunk_size)
    : path_(path), temp_path_(path + ".tmp." + std::to_string(::getpid())), chunk_size_(chunk_size) {
  file_ = std::fopen(temp_path_.c_str(), "wb");
  if (file_ == nullptr) throw std::runtime_error("mcap: cannot create '" + path + "': " + std::strerror(errno));
  write(std::string(kMagic, sizeof kMagic), &data_crc_);
  write(Bytes().str(profile).str(library).record(Opcode::kHeader), &data_crc_);
}

McapWriter::~McapWriter() {
  if (file_ != nullptr) std::fclose(file_);
  if (!closed_) std::remove(temp_path_.c_str());
}

void McapWriter::write(const std::string& bytes, Crc32* crc) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    throw std::runtime_error("mcap: writing '" + path_ + "' failed: " + std::strerror(errno));
  }
  if (crc != nullptr) crc->update(bytes.data(), bytes.size());
  position_ += bytes.size();
}

uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  const auto id = static_cast<uint16_t>(schema_records_.size() + 1);  // 0 means "no schema"
  const std::string record = Bytes().u16(id).str(name).str(encoding).str(data).record(Opcode::kSchema);
  // In the data section (outside chunks, before any message that needs it)
  // and again in the summary, for readers that start there.
  write(record, &data_crc_);
  schema_records_.push_back(record);
  return id;
}

uint16_t McapWriter::add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding) {
  const auto id = static_cast<uint16_t>(channel_records_.size() + 1);
  const std::string no_metadata = Bytes().u32(0).bytes();
  const std::string record =
      Bytes().u16(id).u16(schema_id).str(topic).str(message_encoding).raw(no_metadata).record(Opcode::kChannel);
  write(record, &data_crc_);
  channel_records_.push_back(record);
  return id;
}

void McapWriter::add_message(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const std::string& data) {
  if (chunk_.empty()) chunk_start_time_ = chunk_end_time_ = log_time;
  chunk_start_time_ = std::min(chunk_start_time_, log_time);
  chunk_end_time_ = std::max(chunk_end_time_, log_time);
  chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
  const uint32_t sequence = next_sequence_[channel_id]++;
  chunk_ += Bytes().u16(channel_id).u32(sequence).u64(log_time).u64(publish_time).raw(data).record(Opcode::kMessage);

  if (stats_.message_count == 0) stats_.message_start_time = stats_.message_end_time = log_time;
  ++stats_.message_count;
  stats_.message_start_time = std::min(stats_.message_start_time, log_time);
  stats_.message_end_time = std::max(stats_.message_end_time, log_time);
  ++stats_.channel_message_counts[channel_id];
  if (chunk_.size() >= chunk_size_) flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  ChunkIndexEntry entry;
  entry.start_time = chunk_start_time_;
  entry.end_time = chunk_end_time_;
  entry.offset = position_;
  entry.size = chunk_.size();
  const std::string record = Bytes()
                                 .u64(chunk_start_time_)
                                 .u64(chunk_end_time_)
                                 .u64(chunk_.size())
                                 .u32(crc32(chunk_.data(), chunk_.size()))
                                 .str("")  // no compression
                                 .u64(chunk_.size())
                                 .raw(chunk_)
                                 .record(Opcode::kChunk);
  write(record, &data_crc_);
  entry.length = record.size();

  // One message index per channel of the chunk, in channel order, each
  // sorted by log time (the order readers merge in).
  const uint64_t indexes_start = position_;
  for (auto& [channel, entries] : chunk_index_) {
    std::stable_sort(entries.begin(), entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    Bytes list;
    for (const auto& [time, offset] : entries) list.u64(time).u64(offset);
    entry.message_index_offsets[channel] = position_;
    write(Bytes().u16(channel).sized(list.bytes()).record(Opcode::kMessageIndex), &data_crc_);
  }
  entry.message_index_length = position_ - indexes_start;
  chunk_indexes_.push_back(std::move(entry));
  ++stats_.chunk_count;
  chunk_.clear();
  chunk_index_.clear();
}

// Writes a group of summary records; remembers its Summary Offset record.
std::string McapWriter::summary_group(uint8_t opcode, const std::vector<std::string>& records,
                                      std::vector<std::string>& offsets) {
  std::string group;
  for (const auto& r : records) group += r;
  if (!group.empty()) {
    offsets.push_back(Bytes().u8(opcode).u64(position_).u64(group.size()).record(Opcode::kSummaryOffset));
  }
  return group;
}

void McapWriter::close() {
  if (closed_) return;
  flush_chunk();
  write(Bytes().u32(data_crc_.value()).record(Opcode::kDataEnd), nullptr);

  Crc32 summary_crc;
  const uint64_t summary_start = position_;
  std::vector<std::string> offsets;
  auto write_group = [&](Opcode op, const std::vector<std::string>& records) {
    write(summary_group(static_cast<uint8_t>(op), records, offsets), &summary_crc);
  };
  write_group(Opcode::kSchema, schema_records_);
  write_group(Opcode::kChannel, channel_records_);

  Bytes counts;
  for (const auto& [channel, n] : stats_.channel_message_counts) counts.u16(channel).u64(n);
  write_group(Opcode::kStatistics, {Bytes()
                                         .u64(stats_.message_count)
                                         .u16(static_cast<uint16_t>(schema_records_.size()))
                                         .u32(static_cast<uint32_t>(channel_records_.size()))
                                         .u32(0)  // attachments
                                         .u32(0)  // metadata
                                         .u32(stats_.chunk_count)
                                         .u64(stats_.message_start_time)
                                         .u64(stats_.message_end_time)
                                         .sized(counts.bytes())
                                         .record(Opcode::kStatistics)});

  std::vector<std::string> chunk_index_records;
  for (const auto& c : chunk_indexes_) {
    Bytes offsets_map;
    for (const auto& [channel, offset] : c.message_index_offsets) offsets_map.u16(channel).u64(offset);
    chunk_index_records.push_back(Bytes()
                                      .u64(c.start_time)
                                      .u64(c.end_time)
                                      .u64(c.offset)
                                      .u64(c.length)
                                      .sized(offsets_map.bytes())
                                      .u64(c.message_index_length)
                                      .str("")
                                      .u64(c.size)
                                      .u64(c.size)
                                      .record(Opcode::kChunkIndex));
  }
  write_group(Opcode::kChunkIndex, chunk_index_records);

  const uint64_t summary_offset_start = position_;
  for (const auto& o : offsets) write(o, &summary_crc);
  // The footer's CRC covers the summary, the summary offsets and the footer
  // up to and including summary_offset_start.
  const std::string footer_prefix = Bytes().u8(static_cast<uint8_t>(Opcode::kFooter)).u64(8 + 8 + 4).u64(summary_start).u64(summary_offset_start).bytes();
  summary_crc.update(footer_prefix.data(), footer_prefix.size());
  write(footer_prefix + Bytes().u32(summary_crc.value()).bytes(), nullptr);
  write(std::string(kMagic, sizeof kMagic), nullptr);

  const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) throw std::runtime_error("mcap: writing '" + path_ + "' failed: " + std::strerror(errno));
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("mcap: cannot rename the temporary file to '" + path_ + "': " + std::strerror(errno));
  }
  closed_ = true;
}

}  // namespace rigctl::mcap
