// What every fuzz target does with a message it decoded: read all of it, as
// a handler would, so a malformed pointer deep inside fails here too.
#pragma once

#include <capnp/dynamic.h>
#include <kj/exception.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "common/transport/photon_map.h"
#include "common/transport/photon_record.h"
#include "common/net/ray_wire.h"
#include "proto/wire.capnp.h"

namespace portico::fuzz {

// Every field of every struct, list, text and data blob, through Cap'n
// Proto's reflection: each Envelope variant is read without naming it.
inline uint64_t readEverything(capnp::DynamicValue::Reader value) {
  uint64_t touched = 0;
  switch (value.getType()) {
    case capnp::DynamicValue::STRUCT: {
      const auto object = value.as<capnp::DynamicStruct>();
      KJ_IF_MAYBE(field, object.which()) { touched += readEverything(object.get(*field)); }
      for (const auto field : object.getSchema().getNonUnionFields())
        if (object.has(field)) touched += readEverything(object.get(field));
      break;
    }
    case capnp::DynamicValue::LIST:
      for (const auto element : value.as<capnp::DynamicList>()) touched += readEverything(element);
      break;
    case capnp::DynamicValue::TEXT: touched += value.as<capnp::Text>().size(); break;
    case capnp::DynamicValue::DATA:
      for (const kj::byte b : value.as<capnp::Data>()) touched += b;
      break;
    default: ++touched;
  }
  return touched;
}

// Rays as the worker takes them from a batch or a crossing: converted and checked.
inline size_t readRays(capnp::List<wire::Ray>::Reader rays) {
  size_t valid = 0;
  for (const auto ray : rays) valid += isValid(fromWire(ray));
  return valid;
}

// The lattice of the photon tables the targets decode (and the seeds are
// written on): a 20 m cell, power unit 1.
inline const PhotonFrame& photonFrame() {
  static const PhotonFrame frame(Bounds3(Vec3(-10.0f), Vec3(10.0f)), 0.5f, 1.0f);
  return frame;
}

// Photon tables as the worker turns them into a photon map.
inline void buildPhotonMap(const std::vector<StoredPhoton>& photons) {
  if (photons.empty()) return;
  PhotonMap map(photons);
  std::vector<uint32_t> nearest;
  map.nearest(photons.front().position, 4, 1.0f, nearest);
}

}  // namespace portico::fuzz
