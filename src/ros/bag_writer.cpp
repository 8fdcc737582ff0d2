#include "gear_dynamics/ros/bag_writer.hpp"

#include <roslz4/lz4s.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace gear_dynamics {

namespace {

// rosbag's constants (rosbag/constants.h; format 2.0).
constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::uint32_t kFileHeaderLength = 4096;  // the file header record is padded to this
constexpr std::uint32_t kChunkThreshold = 768 * 1024;  // rosbag's default: a chunk ends past this
constexpr int kLz4BlockSizeId = 6;  // rosbag's LZ4Stream
constexpr std::uint8_t kOpMessageData = 0x02, kOpFileHeader = 0x03, kOpIndexData = 0x04, kOpChunkInfo = 0x06,
                       kOpChunk = 0x05, kOpConnection = 0x07;
constexpr std::uint32_t kIndexVersion = 1, kChunkInfoVersion = 1;

// A record header as ros::Header::write makes it from rosbag's M_string (a std::map, so the fields
// come sorted by name): for each field its length, then name=value.
class Fields {
 public:
  template <class T>
  Fields& binary(const char* name, const T& value) {
    return text(name, std::string(reinterpret_cast<const char*>(&value), sizeof value));
  }
  Fields& time(const char* name, const ros::Time& t) {
    std::string v(8, '\0');
    std::memcpy(&v[0], &t.sec, 4);
    std::memcpy(&v[4], &t.nsec, 4);
    return text(name, v);
  }
  Fields& text(const char* name, const std::string& value) {
    fields_[name] = value;
    return *this;
  }
  // The length-prefixed header, appended to `out`.
  template <class Bytes>
  void append(Bytes& out) const {
    std::uint32_t length = 0;
    for (const auto& [name, value] : fields_) length += 4 + static_cast<std::uint32_t>(name.size() + 1 + value.size());
    put(out, &length, 4);
    for (const auto& [name, value] : fields_) {
      const auto field = static_cast<std::uint32_t>(name.size() + 1 + value.size());
      put(out, &field, 4);
      put(out, name.data(), name.size());
      put(out, "=", 1);
      put(out, value.data(), value.size());
    }
  }
  std::string bytes() const {
    std::string out;
    append(out);
    return out;
  }

 private:
  template <class Bytes>
  static void put(Bytes& out, const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    out.insert(out.end(), p, p + size);
  }
  std::map<std::string, std::string> fields_;
};

template <class Bytes>
void append_u32(Bytes& out, std::uint32_t v) {
  const auto* p = reinterpret_cast<const char*>(&v);
  out.insert(out.end(), p, p + 4);
}

}  // namespace

BagWriter::~BagWriter() {
  if (file_) std::fclose(file_);
}

void BagWriter::fail(const std::string& what) {
  const int error = errno;
  throw BagWriteError(path_ + ": " + what + (error ? std::string(": ") + std::strerror(error) : std::string()));
}

void BagWriter::put(const void* data, std::size_t size) {
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) fail("write failed");
  offset_ += size;
}

void BagWriter::open(const std::string& path) {
  if (file_) std::fclose(file_);
  path_ = path;
  errno = 0;
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) fail("cannot create");
  offset_ = 0;
  connections_.clear();
  by_id_.clear();
  chunk_.clear();
  index_.clear();
  chunks_.clear();
  put(kVersionLine, sizeof kVersionLine - 1);
  write_file_header(0);
}

void BagWriter::write_file_header(std::uint64_t index_position) {
  const std::string header = Fields()
                                 .binary("op", kOpFileHeader)
                                 .binary("index_pos", index_position)
                                 .binary("conn_count", static_cast<std::uint32_t>(connections_.size()))
                                 .binary("chunk_count", static_cast<std::uint32_t>(chunks_.size()))
                                 .bytes();
  const std::uint32_t header_length = static_cast<std::uint32_t>(header.size()) - 4;
  const std::uint32_t padding = header_length < kFileHeaderLength ? kFileHeaderLength - header_length : 0;
  std::string record = header;
  append_u32(record, padding);
  record.append(padding, ' ');
  put(record.data(), record.size());
}

std::uint8_t* BagWriter::begin_message(const std::string& topic, const ros::Time& time, const char* type,
                                       const char* md5, const char* definition, std::uint32_t size) {
  if (time < ros::TIME_MIN) throw BagWriteError(path_ + ": a message time before ros::TIME_MIN");
  auto found = connections_.find(topic);
  const bool new_connection = found == connections_.end();
  if (new_connection) {
    Connection c;
    c.id = static_cast<std::uint32_t>(connections_.size());
    c.topic = topic;
    c.header = Fields().text("type", type).text("md5sum", md5).text("message_definition", definition).bytes();
    c.message_header = Fields().binary("op", kOpMessageData).binary("conn", c.id).time("time", ros::Time()).bytes();
    found = connections_.emplace(topic, std::move(c)).first;
    by_id_.push_back(&found->second);
    index_.emplace_back();
  }
  const Connection& c = found->second;
  if (chunk_.empty()) {  // a new chunk starts at the end of the file
    current_ = ChunkInfo();
    current_.position = offset_;
    current_.start = current_.end = time;
  }
  if (new_connection) {  // the connection record goes into the chunk of its first message, as rosbag's
    Fields().binary("op", kOpConnection).text("topic", c.topic).binary("conn", c.id).append(chunk_);
    chunk_.insert(chunk_.end(), c.header.begin(), c.header.end());
  }
  index_[c.id].push_back({time, static_cast<std::uint32_t>(chunk_.size())});
  chunk_.insert(chunk_.end(), c.message_header.begin(), c.message_header.end());
  // Fields sort by name, so "time" is the last field: its 8 bytes end the header.
  std::memcpy(chunk_.data() + chunk_.size() - 8, &time.sec, 4);
  std::memcpy(chunk_.data() + chunk_.size() - 4, &time.nsec, 4);
  append_u32(chunk_, size);
  if (time > current_.end) current_.end = time;
  else if (time < current_.start) current_.start = time;
  const std::size_t at = chunk_.size();
  chunk_.resize(at + size);
  return chunk_.data() + at;
}

void BagWriter::end_message() {
  if (chunk_.size() > kChunkThreshold) write_chunk();
}

void BagWriter::write_chunk() {
  // The chunk record, compressed as rosbag's LZ4Stream does (one roslz4 frame)...
  compressed_.resize(chunk_.size() + chunk_.size() / 255 + 1024);
  unsigned int compressed_size = static_cast<unsigned int>(compressed_.size());
  if (roslz4_buffToBuffCompress(reinterpret_cast<char*>(chunk_.data()), static_cast<unsigned int>(chunk_.size()),
                                compressed_.data(), &compressed_size, kLz4BlockSizeId) != ROSLZ4_OK) {
    errno = 0;
    fail("LZ4 compression failed");
  }
  std::string record = Fields()
                           .binary("op", kOpChunk)
                           .text("compression", "lz4")
                           .binary("size", static_cast<std::uint32_t>(chunk_.size()))
                           .bytes();
  append_u32(record, compressed_size);
  put(record.data(), record.size());
  put(compressed_.data(), compressed_size);
  // ... then its index: per connection, the messages' times and offsets in the chunk, time-ordered
  // (rosbag keeps a multiset, equal times in insertion order).
  std::string index;
  for (std::uint32_t id = 0; id < index_.size(); ++id) {
    std::vector<IndexEntry>& entries = index_[id];
    if (entries.empty()) continue;  // no message of this connection in the chunk
    current_.counts[id] = static_cast<std::uint32_t>(entries.size());
    std::stable_sort(entries.begin(), entries.end(), [](const IndexEntry& a, const IndexEntry& b) { return a.time < b.time; });
    Fields()
        .binary("op", kOpIndexData)
        .binary("conn", id)
        .binary("ver", kIndexVersion)
        .binary("count", static_cast<std::uint32_t>(entries.size()))
        .append(index);
    append_u32(index, static_cast<std::uint32_t>(entries.size() * 12));
    for (const IndexEntry& e : entries) {
      append_u32(index, e.time.sec);
      append_u32(index, e.time.nsec);
      append_u32(index, e.offset);
    }
  }
  put(index.data(), index.size());
  chunks_.push_back(current_);
  chunk_.clear();
  for (std::vector<IndexEntry>& entries : index_) entries.clear();
}

void BagWriter::close() {
  if (!file_) return;
  if (!chunk_.empty()) write_chunk();
  const std::uint64_t index_position = offset_;
  std::string tail;
  for (const Connection* c : by_id_) {
    Fields().binary("op", kOpConnection).text("topic", c->topic).binary("conn", c->id).append(tail);
    tail += c->header;
  }
  for (const ChunkInfo& k : chunks_) {
    Fields()
        .binary("op", kOpChunkInfo)
        .binary("ver", kChunkInfoVersion)
        .binary("chunk_pos", k.position)
        .time("start_time", k.start)
        .time("end_time", k.end)
        .binary("count", static_cast<std::uint32_t>(k.counts.size()))
        .append(tail);
    append_u32(tail, static_cast<std::uint32_t>(8 * k.counts.size()));
    for (const auto& [id, count] : k.counts) {
      append_u32(tail, id);
      append_u32(tail, count);
    }
  }
  put(tail.data(), tail.size());
  errno = 0;
  if (std::fseek(file_, sizeof kVersionLine - 1, SEEK_SET) != 0) fail("seek failed");
  write_file_header(index_position);
  std::FILE* f = file_;
  file_ = nullptr;
  errno = 0;
  if (std::fclose(f) != 0) fail("close failed");
}

}  // namespace gear_dynamics
