#include "common/net/message.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

namespace portico::net {

namespace {
// See maxCoordinatorFrameBytes: measured and reasoned in docs/architecture.md.
constexpr uint64_t kCoordinatorFrameFloorBytes = uint64_t(16) << 20;
constexpr uint64_t kCoordinatorFrameBytesPerLeaseRay = 2048;
}  // namespace

namespace {
// A flat frame's first word. A packed message never starts with 0xff: its
// first word is the segment table, whose bytes 1-3 (the high bytes of the
// segment count) are zero, so its packing tag has those bits clear.
constexpr unsigned char kFlatMarker[8] = {0xff, 'F', 'L', 'A', 'T', 0, 0, 1};

// Bytes of the flat encoding of a message: the marker, then its words.
size_t flatSize(capnp::MessageBuilder& message) {
  return sizeof(kFlatMarker) + capnp::computeSerializedSizeInWords(message) * sizeof(capnp::word);
}
void writeFlat(capnp::MessageBuilder& message, kj::byte* into, size_t size) {
  std::memcpy(into, kFlatMarker, sizeof(kFlatMarker));
  kj::ArrayOutputStream out(kj::arrayPtr(into + sizeof(kFlatMarker), size - sizeof(kFlatMarker)));
  capnp::writeMessage(out, message);
}
}  // namespace

zmq::message_t encode(capnp::MessageBuilder& message, Encoding encoding) {
  if (encoding == Encoding::Flat) {
    zmq::message_t frame(flatSize(message));
    writeFlat(message, static_cast<kj::byte*>(frame.data()), frame.size());
    return frame;
  }
  kj::VectorOutputStream stream;
  capnp::writePackedMessage(stream, message);
  auto bytes = stream.getArray();
  return zmq::message_t(bytes.begin(), bytes.size());
}

std::string flatToString(capnp::MessageBuilder& message) {
  std::string bytes(flatSize(message), '\0');
  writeFlat(message, reinterpret_cast<kj::byte*>(bytes.data()), bytes.size());
  return bytes;
}

std::string packToString(capnp::MessageBuilder& message) {
  kj::VectorOutputStream stream;
  capnp::writePackedMessage(stream, message);
  auto bytes = stream.getArray();
  return std::string(reinterpret_cast<const char*>(bytes.begin()), bytes.size());
}

uint64_t maxCoordinatorFrameBytes(int64_t leaseRays) {
  return kCoordinatorFrameFloorBytes + uint64_t(std::max<int64_t>(leaseRays, 1)) * kCoordinatorFrameBytesPerLeaseRay;
}

namespace {
constexpr unsigned kMaxSegments = 512;   // Cap'n Proto refuses more

capnp::ReaderOptions optionsFor(size_t packedBytes) {
  // The traversal limit stops amplification (a small frame pointing at the
  // same data many times, or zero runs that unpack 2 bytes into 256 words),
  // and it also caps what the reader allocates for the segments a frame
  // claims. portico's messages are floats and ids, with few zero words: one
  // word per packed byte (8x the frame) is more than any of them needs. The
  // floor (512 KiB) is for tiny messages; a floor of 8 MiB would let a
  // 10-byte garbage frame make the coordinator allocate and zero 8 MiB.
  capnp::ReaderOptions options;
  options.traversalLimitInWords = packedBytes + (size_t(1) << 16);
  options.nestingLimit = 16;
  return options;
}
}  // namespace

PackedReader::PackedReader(const void* data, size_t bytes)
    : input_(kj::ArrayPtr<const kj::byte>(static_cast<const kj::byte*>(data), bytes)) {
  try {
    reader_ = std::make_unique<capnp::PackedMessageReader>(input_, optionsFor(bytes));
    // Read every segment now. Cap'n Proto reads the later segments of a
    // multi-segment message lazily and skips what is left of it in its
    // destructor: on a truncated frame that skip throws from a destructor,
    // and the process ends (found by tests/fuzz/fuzz_ray_batch). Here the
    // same failure is still an error we can report; and if it happens, the
    // reader is destroyed while this exception unwinds, when it keeps quiet.
    for (unsigned segment = 1; segment < kMaxSegments && reader_->getSegment(segment).begin() != nullptr; ++segment) {
    }
  } catch (const kj::Exception& e) {
    throw std::runtime_error(fmt::format("malformed message: {}", e.getDescription().cStr()));
  }
}

MessageReader::MessageReader(const void* data, size_t size) {
  if (size == 0) throw std::runtime_error("malformed message: empty");
  const auto* bytes = static_cast<const kj::byte*>(data);
  if (bytes[0] != kFlatMarker[0]) {
    packed_ = std::make_unique<PackedReader>(data, size);
    return;
  }
  if (size < sizeof(kFlatMarker) || std::memcmp(bytes, kFlatMarker, sizeof(kFlatMarker)) != 0)
    throw std::runtime_error("malformed message: unknown encoding");
  const size_t payload = size - sizeof(kFlatMarker);
  if (payload % sizeof(capnp::word) != 0 || payload == 0)
    throw std::runtime_error(fmt::format("malformed message: a flat frame of {} bytes is not whole words", payload));
  const kj::byte* first = bytes + sizeof(kFlatMarker);
  kj::ArrayPtr<const capnp::word> words;
  if (reinterpret_cast<uintptr_t>(first) % alignof(capnp::word) == 0) {
    words = kj::arrayPtr(reinterpret_cast<const capnp::word*>(first), payload / sizeof(capnp::word));
  } else {
    words_ = kj::heapArray<capnp::word>(payload / sizeof(capnp::word));
    std::memcpy(words_.begin(), first, payload);
    words = words_.asPtr();
  }
  try {
    flat_ = std::make_unique<capnp::FlatArrayMessageReader>(words, optionsFor(size));
    if (flat_->getEnd() != words.end()) throw std::runtime_error("malformed message: a flat frame longer than its message");
  } catch (const kj::Exception& e) {
    throw std::runtime_error(fmt::format("malformed message: {}", e.getDescription().cStr()));
  }
}

Decoded::Decoded(const zmq::message_t& frame) : frame_(frame.data(), frame.size()) { decode(frame_.data(), frame_.size()); }

Decoded::Decoded(zmq::message_t&& frame) : frame_(std::move(frame)) { decode(frame_.data(), frame_.size()); }

void Decoded::decode(const void* data, size_t bytes) {
  if (bytes > kMaxFrameBytes)
    throw std::runtime_error(
        fmt::format("malformed message: {} bytes is over the {} byte limit", bytes, kMaxFrameBytes));
  if (bytes == 0) throw std::runtime_error("malformed message: empty frame");
  reader_ = std::make_unique<MessageReader>(data, bytes);
  envelope_ = reader_->root<wire::Envelope>();
  try {
    (void)envelope_.which();   // a malformed root fails here, not deep in a handler
  } catch (const kj::Exception& e) {
    throw std::runtime_error(fmt::format("malformed message: {}", e.getDescription().cStr()));
  }
}

}  // namespace portico::net
