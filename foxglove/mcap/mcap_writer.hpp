// An MCAP file writer after the MCAP specification (docs/foxglove.md):
// magic, header, schemas and channels, messages in uncompressed chunks each
// followed by its message indexes, data end with the data section's CRC, a
// summary (schemas, channels, statistics, chunk indexes), summary offsets,
// footer with the summary's CRC, magic. Readers that seek (Foxglove,
// PlotJuggler) need the indexes and the summary; the CRCs let them check.
//
// The file is written under a temporary name and renamed into place by
// close(): a crash never leaves a half-written MCAP under the final name.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "foxglove/mcap/crc32.hpp"

namespace rigctl::mcap {

struct McapStatistics {
  uint64_t message_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

class McapWriter {
 public:
  // A chunk of 512 KiB holds about half a second of every rigctl channel as
  // JSON at 400 Hz: a reader seeking to a time reads at most that much more.
  static constexpr std::size_t kDefaultChunkSize = 512 * 1024;

  // Throws std::runtime_error naming the path when it cannot be created.
  McapWriter(const std::string& path, const std::string& profile, const std::string& library,
             std::size_t chunk_size = kDefaultChunkSize);
  ~McapWriter();  // without close(): the temporary file is removed
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding);
  // Messages should come in log-time order (a chunk's index is sorted anyway).
  void add_message(uint16_t channel_id, uint64_t log_time, uint64_t publish_time, const std::string& data);
  // Writes the last chunk, the summary and the footer, and renames the file
  // into place. Throws std::runtime_error when a write failed.
  void close();

  const McapStatistics& statistics() const { return stats_; }

 private:
  struct ChunkIndexEntry {
    uint64_t start_time = 0, end_time = 0, offset = 0, length = 0;
    std::map<uint16_t, uint64_t> message_index_offsets;
    uint64_t message_index_length = 0;
    uint64_t size = 0;  // uncompressed = compressed: no compression
  };

  void write(const std::string& bytes, Crc32* crc);
  void flush_chunk();
  std::string summary_group(uint8_t opcode, const std::vector<std::string>& records,
                            std::vector<std::string>& offsets);

  std::string path_, temp_path_;
  std::FILE* file_ = nullptr;
  uint64_t position_ = 0;
  std::size_t chunk_size_;
  Crc32 data_crc_;
  std::vector<std::string> schema_records_, channel_records_;
  std::map<uint16_t, uint32_t> next_sequence_;
  // The chunk being filled: its records, and per channel (log time, offset).
  std::string chunk_;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;
  uint64_t chunk_start_time_ = 0, chunk_end_time_ = 0;
  std::vector<ChunkIndexEntry> chunk_indexes_;
  McapStatistics stats_;
  bool closed_ = false;
};

}  // namespace rigctl::mcap
