// JobSettings (common/job/job_settings.h) and their wire form (wire::JobSpec).
#pragma once

#include "common/job/job_settings.h"
#include "proto/wire.capnp.h"

namespace portico {

void toWire(const JobSettings& settings, wire::JobSpec::Builder spec);
// The settings as the message holds them: a submit message's automatic
// values stay automatic until the coordinator resolves them.
JobSettings jobSettingsFromWire(wire::JobSpec::Reader spec);

}  // namespace portico
