#include "common/net/message.h"

#include <gtest/gtest.h>

#include <random>

namespace portico {
namespace {

TEST(Message, RoundTripsAnEnvelope) {
  capnp::MallocMessageBuilder message;
  auto hello = message.initRoot<wire::Envelope>().initHello();
  hello.setVersion(wire::PROTOCOL_VERSION);
  hello.setName("worker-a");
  hello.setCores(4);
  zmq::message_t frame = net::encode(message);
  net::Decoded decoded(frame);
  ASSERT_EQ(decoded.envelope().which(), wire::Envelope::HELLO);
  EXPECT_EQ(std::string(decoded.envelope().getHello().getName().cStr()), "worker-a");
  EXPECT_EQ(decoded.envelope().getHello().getCores(), 4u);
}

TEST(Message, RoundTripsAFlatResultWithItsPhotonTables) {
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Envelope>().initResult();
  result.setLease(77);
  const std::string records(24 * 1000, '\x5a');
  auto deposits = result.initDeposits(1);
  deposits[0].setCell(3);
  deposits[0].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()), records.size()));
  const zmq::message_t flat = net::encode(message, net::Encoding::Flat);
  const zmq::message_t packed = net::encode(message);
  EXPECT_EQ(static_cast<const unsigned char*>(flat.data())[0], 0xff);
  EXPECT_NE(static_cast<const unsigned char*>(packed.data())[0], 0xff);
  for (const zmq::message_t* frame : {&flat, &packed}) {
    net::Decoded decoded(*frame);
    ASSERT_EQ(decoded.envelope().which(), wire::Envelope::RESULT);
    auto got = decoded.envelope().getResult();
    EXPECT_EQ(got.getLease(), 77u);
    ASSERT_EQ(got.getDeposits().size(), 1u);
    EXPECT_EQ(got.getDeposits()[0].getCell(), 3u);
    auto bytes = got.getDeposits()[0].getRecords();
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(bytes.begin()), bytes.size()), records);
  }
}

// A frame handed over (an rvalue) is read in place and kept alive with the
// envelope; the bytes read are the frame's own.
TEST(Message, AFrameHandedOverIsReadInPlace) {
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Envelope>().initResult();
  result.setLease(9);
  const std::string records(24 * 50, '\x21');
  auto deposits = result.initDeposits(1);
  deposits[0].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()), records.size()));
  zmq::message_t frame = net::encode(message, net::Encoding::Flat);
  const auto* begin = static_cast<const kj::byte*>(frame.data());
  const auto* end = begin + frame.size();
  net::Decoded decoded(std::move(frame));
  auto bytes = decoded.envelope().getResult().getDeposits()[0].getRecords();
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(bytes.begin()), bytes.size()), records);
  if (reinterpret_cast<uintptr_t>(begin) % 8 == 0) {   // ZeroMQ's allocation: aligned
    EXPECT_GE(bytes.begin(), begin);
    EXPECT_LE(bytes.end(), end);
  }
}

// Stored blobs (jobs.db rows and batch files) are packed or flat; one
// reader reads both, from aligned or unaligned bytes, and refuses a cut one.
TEST(Message, StoredBlobsOfEitherEncodingReadBackFromAnyAlignment) {
  capnp::MallocMessageBuilder message;
  auto rays = message.initRoot<wire::RayBatch>().initRays(3);
  for (unsigned i = 0; i < 3; ++i) rays[i].setPathId(100 + i);
  for (const std::string& blob : {net::packToString(message), net::flatToString(message)}) {
    for (size_t shift : {0, 1, 3, 8}) {
      const std::string shifted = std::string(shift, '\0') + blob;
      net::MessageReader reader(shifted.data() + shift, blob.size());
      auto read = reader.root<wire::RayBatch>().getRays();
      ASSERT_EQ(read.size(), 3u);
      EXPECT_EQ(read[2].getPathId(), 102u);
    }
    EXPECT_THROW(net::MessageReader(blob.data(), blob.size() - 8).root<wire::RayBatch>(), std::runtime_error);
  }
  EXPECT_GT(net::flatToString(message).size(), net::packToString(message).size());
}

TEST(Message, RejectsFlatFramesThatAreNotWholeOrNotOurs) {
  capnp::MallocMessageBuilder message;
  message.initRoot<wire::Envelope>().initResult().setLease(5);
  const zmq::message_t whole = net::encode(message, net::Encoding::Flat);
  int refused = 0;
  for (size_t length = 1; length < whole.size(); ++length) {
    const zmq::message_t cut(whole.data(), length);
    try {
      net::Decoded decoded(cut);
      (void)decoded.envelope().getResult().getLease();
    } catch (const std::runtime_error&) {
      ++refused;
    }
  }
  EXPECT_EQ(refused, int(whole.size()) - 1);
  std::string longer(static_cast<const char*>(whole.data()), whole.size());
  longer.append(8, '\0');   // a word beyond the message
  EXPECT_THROW(net::Decoded{zmq::message_t(longer.data(), longer.size())}, std::runtime_error);
  std::string marker = longer.substr(0, whole.size());
  marker[1] = 'X';            // 0xff, then not our marker
  EXPECT_THROW(net::Decoded{zmq::message_t(marker.data(), marker.size())}, std::runtime_error);
}

TEST(Message, RejectsAnEmptyFrame) {
  zmq::message_t frame;
  EXPECT_THROW(net::Decoded{frame}, std::runtime_error);
}

TEST(Message, GarbageNeverCrashesTheDecoder) {
  // Random bytes either fail with std::runtime_error or decode to something
  // whose fields can be read without undefined behaviour.
  std::mt19937 random(12345);
  int rejected = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string bytes(1 + random() % 200, '\0');
    for (char& c : bytes) c = static_cast<char>(random());
    zmq::message_t frame(bytes.data(), bytes.size());
    try {
      net::Decoded decoded(frame);
      auto envelope = decoded.envelope();
      if (envelope.which() == wire::Envelope::RESULT) (void)envelope.getResult().getCrossings().size();
    } catch (const std::runtime_error&) {
      ++rejected;
    } catch (const kj::Exception&) {
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 0);
}

TEST(Message, TraversalLimitStopsAmplification) {
  // A list of 2^20 empty structs packs to a handful of bytes but would make
  // a reader walk a million elements: the limit, sized from the frame, refuses it.
  capnp::MallocMessageBuilder message;
  auto result = message.initRoot<wire::Envelope>().initResult();
  result.initFilm(1u << 20);
  zmq::message_t frame = net::encode(message);
  ASSERT_LT(frame.size(), 200000u);
  EXPECT_ANY_THROW(
      {
        net::Decoded decoded(frame);
        auto film = decoded.envelope().getResult().getFilm();
        int64_t sum = 0;
        for (auto p : film) sum += p.getR();
        (void)sum;
      });
  // Flat, the same list takes its full 24 MiB on the wire: the frame holds
  // every word it asks the reader to walk, and it decodes.
  const zmq::message_t flat = net::encode(message, net::Encoding::Flat);
  ASSERT_GT(flat.size(), size_t(1) << 24);
  net::Decoded decoded(flat);
  EXPECT_EQ(decoded.envelope().getResult().getFilm().size(), 1u << 20);
}

TEST(Message, ATruncatedMultiSegmentMessageIsAnErrorNotACrash) {
  // Small fixed segments: the Result spans many of them, whose later ones
  // Cap'n Proto would read lazily (and skip, throwing, in its destructor).
  capnp::MallocMessageBuilder message(64, capnp::AllocationStrategy::FIXED_SIZE);
  auto crossings = message.initRoot<wire::Envelope>().initResult().initCrossings(40);
  for (unsigned c = 0; c < crossings.size(); ++c) {
    crossings[c].setCell(c);
    auto rays = crossings[c].initRays(4);
    for (unsigned i = 0; i < rays.size(); ++i) rays[i].setOx(float(i) + 0.5f);
  }
  ASSERT_GT(message.getSegmentsForOutput().size(), 4u);
  const zmq::message_t whole = net::encode(message);
  int refused = 0;
  for (size_t length = 8; length < whole.size(); length += whole.size() / 16) {
    const zmq::message_t cut(whole.data(), length);
    try {
      net::Decoded decoded(cut);
      for (auto crossing : decoded.envelope().getResult().getCrossings())
        for (auto ray : crossing.getRays()) (void)ray.getOx();
    } catch (const std::runtime_error&) {
      ++refused;
    } catch (const kj::Exception&) {
      ++refused;
    }
  }
  EXPECT_EQ(refused, 16);
  // The packed blobs of jobs.db go through the same reader.
  const std::string packed(static_cast<const char*>(whole.data()), whole.size() / 2);
  EXPECT_THROW(net::PackedReader(packed.data(), packed.size()), std::runtime_error);
}

}  // namespace
}  // namespace portico
