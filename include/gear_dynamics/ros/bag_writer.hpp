// A ROS 1 bag writer (format 2.0, LZ4 chunks) for the batch bags: the same bytes as rosbag::Bag with
// setCompression(LZ4) and the default chunk threshold writes for the same calls (test_batch_io
// compares them), at a fraction of the cost. rosbag::Bag::write seeks to the end of the file twice
// per message (glibc answers each seek with an fstat, an lseek and a read) and builds three header
// maps; here a chunk is assembled in memory and written once, compressed with roslz4 as rosbag
// does. Only what the batch needs: messages by topic (one connection per topic, its header
// type/md5sum/message_definition as rosbag makes it without a connection header), no encryption,
// no append, no reading (rosbag reads the bags).
#pragma once

#include <ros/serialization.h>
#include <ros/time.h>

#include <cstdint>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace gear_dynamics {

// A bag could not be written: "<file>: <what> [: <errno text>]".
class BagWriteError : public std::runtime_error {
 public:
  explicit BagWriteError(const std::string& what) : std::runtime_error(what) {}
};

class BagWriter {
 public:
  BagWriter() = default;
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;
  ~BagWriter();  // closes the file without finishing the bag (call close() to finish it)

  // Creates (truncates) `path` and writes the version line and a provisional file header.
  // Throws BagWriteError.
  void open(const std::string& path);
  bool is_open() const { return file_ != nullptr; }

  template <class M>
  void write(const std::string& topic, const ros::Time& time, const M& message) {
    const std::uint32_t size = ros::serialization::serializationLength(message);
    std::uint8_t* data = begin_message(topic, time, ros::message_traits::datatype(message),
                                       ros::message_traits::md5sum(message), ros::message_traits::definition(message),
                                       size);
    ros::serialization::OStream stream(data, size);
    ros::serialization::serialize(stream, message);
    end_message();
  }

  // Writes the last chunk, the index (connection and chunk info records) and the final file header,
  // then closes the file. Throws BagWriteError.
  void close();

 private:
  struct Connection {
    std::uint32_t id = 0;
    std::string topic, header;  // header: the connection header fields as rosbag stores them
    // The header of this connection's message records, its time field last (patched per message):
    // built once, so that a message costs a copy, not a map of fields.
    std::string message_header;
  };
  struct IndexEntry {
    ros::Time time;
    std::uint32_t offset;
  };
  struct ChunkInfo {
    std::uint64_t position = 0;
    ros::Time start, end;
    std::map<std::uint32_t, std::uint32_t> counts;  // messages per connection (set when the chunk is written)
  };

  std::uint8_t* begin_message(const std::string& topic, const ros::Time& time, const char* type, const char* md5,
                              const char* definition, std::uint32_t size);
  void end_message();
  void write_chunk();
  void write_file_header(std::uint64_t index_position);
  void put(const void* data, std::size_t size);
  void fail(const std::string& what);

  std::FILE* file_ = nullptr;
  std::string path_;
  std::uint64_t offset_ = 0;  // bytes written so far
  std::map<std::string, Connection> connections_;  // by topic
  std::vector<const Connection*> by_id_;
  std::vector<std::uint8_t> chunk_;  // the open chunk, uncompressed
  std::vector<char> compressed_;
  ChunkInfo current_;
  std::vector<std::vector<IndexEntry>> index_;  // the open chunk's, per connection id
  std::vector<ChunkInfo> chunks_;
};

}  // namespace gear_dynamics
