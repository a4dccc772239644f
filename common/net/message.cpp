#include "common/net/message.h"

#include <fmt/format.h>

namespace portico::net {

zmq::message_t encode(capnp::MessageBuilder& message) {
  kj::VectorOutputStream stream;
  capnp::writePackedMessage(stream, message);
  auto bytes = stream.getArray();
  return zmq::message_t(bytes.begin(), bytes.size());
}

std::string packToString(capnp::MessageBuilder& message) {
  kj::VectorOutputStream stream;
  capnp::writePackedMessage(stream, message);
  auto bytes = stream.getArray();
  return std::string(reinterpret_cast<const char*>(bytes.begin()), bytes.size());
}

namespace {
capnp::ReaderOptions optionsFor(size_t packedBytes) {
  // The traversal limit stops amplification (a small frame pointing at the
  // same data many times). Packing compresses at most ~8x for zero-heavy
  // data, so a legitimate message never traverses more than that.
  capnp::ReaderOptions options;
  options.traversalLimitInWords = packedBytes + (size_t(1) << 20);
  options.nestingLimit = 16;
  return options;
}
}  // namespace

PackedReader::PackedReader(const void* data, size_t bytes)
    : input_(kj::ArrayPtr<const kj::byte>(static_cast<const kj::byte*>(data), bytes)), buffered_(input_) {
  try {
    reader_ = std::make_unique<capnp::PackedMessageReader>(buffered_, optionsFor(bytes));
  } catch (const kj::Exception& e) {
    throw std::runtime_error(fmt::format("malformed message: {}", e.getDescription().cStr()));
  }
}

Decoded::Decoded(const zmq::message_t& frame) {
  if (frame.size() == 0) throw std::runtime_error("malformed message: empty frame");
  if (frame.size() > kMaxFrameBytes)
    throw std::runtime_error(
        fmt::format("malformed message: {} bytes is over the {} byte limit", frame.size(), kMaxFrameBytes));
  bytes_.assign(static_cast<const char*>(frame.data()), frame.size());
  reader_ = std::make_unique<PackedReader>(bytes_.data(), bytes_.size());
  envelope_ = reader_->root<wire::Envelope>();
  try {
    (void)envelope_.which();   // a malformed root fails here, not deep in a handler
  } catch (const kj::Exception& e) {
    throw std::runtime_error(fmt::format("malformed message: {}", e.getDescription().cStr()));
  }
}

}  // namespace portico::net
