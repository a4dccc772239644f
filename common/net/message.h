// Cap'n Proto envelopes over ZeroMQ frames, with traversal limits sized for
// legitimate messages. Two encodings: packed (Cap'n Proto's packing: zero
// bytes squeezed out), and flat (a marker word, then the message's words as
// they are), which costs neither side a pass over the bytes. Workers send
// their Results flat: their bulk is photon records and rays, which packing
// shrinks by a tenth at the price of a byte-by-byte pass on each side (5 %
// of a photon pass's CPU). The coordinator's leases (rays) and photon
// replies (records) go flat for the same reason. Everything else goes packed.
#pragma once

#include <capnp/message.h>
#include <capnp/serialize-packed.h>
#include <capnp/serialize.h>
#include <kj/io.h>

#include <stdexcept>

#include <memory>
#include <string>
#include <zmq.hpp>

#include "proto/wire.capnp.h"

namespace portico::net {

// Largest frame a worker or client accepts (a coordinator's photon reply can
// hold a whole cell's photon table). The coordinator's own, smaller limit is
// maxCoordinatorFrameBytes.
constexpr size_t kMaxFrameBytes = size_t(512) << 20;

// The coordinator's Error to a worker it does not know (it restarted since
// the worker's Hello): the worker says Hello again at once.
inline constexpr const char* kUnknownWorkerError = "unknown worker: say Hello first";

// The largest frame a coordinator accepts (ZMQ_MAXMSGSIZE): a worker's Result
// for a lease of `leaseRays` rays, with room for the fan-out of final
// gathering, shadow rays and photon deposits (docs/security.md, "Message limits").
uint64_t maxCoordinatorFrameBytes(int64_t leaseRays);

enum class Encoding { Packed, Flat };
zmq::message_t encode(capnp::MessageBuilder& message, Encoding encoding = Encoding::Packed);

// Reads a packed message from bytes that stay alive as long as this reader.
// Unpacking copies into fresh word arrays, so the input need not be aligned.
// Throws std::runtime_error("malformed message: ...") on bad input.
class PackedReader {
 public:
  PackedReader(const void* data, size_t bytes);
  template <typename T>
  typename T::Reader root() {
    try {
      return reader_->getRoot<T>();
    } catch (const kj::Exception& e) {
      throw std::runtime_error(std::string("malformed message: ") + e.getDescription().cStr());
    }
  }

 private:
  kj::ArrayInputStream input_;   // buffered already: the packed reader reads it in place
  std::unique_ptr<capnp::PackedMessageReader> reader_;
};

// Reads a message of either encoding from bytes that stay alive as long as
// this reader: frames, and the blobs kept in jobs.db and its files. A flat
// message is read in place where its words are 8-byte aligned (ZeroMQ's
// and malloc's allocations are), else after one copy to aligned words.
// Throws std::runtime_error("malformed message: ...") on bad input.
class MessageReader {
 public:
  MessageReader(const void* data, size_t bytes);
  template <typename T>
  typename T::Reader root() {
    try {
      return packed_ ? packed_->root<T>() : flat_->getRoot<T>();
    } catch (const kj::Exception& e) {
      throw std::runtime_error(std::string("malformed message: ") + e.getDescription().cStr());
    }
  }

 private:
  std::unique_ptr<PackedReader> packed_;
  kj::Array<capnp::word> words_;   // a copy of unaligned flat words
  std::unique_ptr<capnp::FlatArrayMessageReader> flat_;
};

// A decoded envelope from one ZeroMQ frame of either encoding. Handed the
// frame (an rvalue), it keeps it and reads a flat one in place; from a
// const frame, it reads a copy, and nothing refers to the frame after.
class Decoded {
 public:
  explicit Decoded(const zmq::message_t& frame);
  explicit Decoded(zmq::message_t&& frame);
  wire::Envelope::Reader envelope() const { return envelope_; }

 private:
  void decode(const void* data, size_t bytes);

  zmq::message_t frame_;   // the frame, or a copy of it
  std::unique_ptr<MessageReader> reader_;
  wire::Envelope::Reader envelope_;
};

// A standalone message as bytes (for blobs stored in jobs.db and its files),
// packed or flat; MessageReader reads both.
std::string packToString(capnp::MessageBuilder& message);
std::string flatToString(capnp::MessageBuilder& message);

}  // namespace portico::net
