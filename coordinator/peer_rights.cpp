#include "coordinator/peer_rights.h"

#include <fmt/format.h>

namespace portico {

namespace {
using Which = wire::Envelope::Which;

bool workerMay(Which type) {
  switch (type) {
    case Which::HELLO:
    case Which::READY:
    case Which::HEARTBEAT:
    case Which::RESULT:
    case Which::FAILURE:
    case Which::FETCH_PHOTONS:
    case Which::FETCH_FILE:
    case Which::GOODBYE: return true;
    default: return false;
  }
}

bool clientMay(Which type) {
  switch (type) {
    case Which::SUBMIT:
    case Which::STATUS:
    case Which::CANCEL:
    case Which::PRIORITY:
    case Which::FETCH_IMAGE:
    case Which::JOB_DETAIL:
    case Which::FETCH_PREVIEW:
    case Which::HEARTBEAT: return true;
    default: return false;
  }
}

std::string_view nameOf(Which type) {
  switch (type) {
    case Which::HELLO: return "Hello";
    case Which::READY: return "Ready";
    case Which::RESULT: return "Result";
    case Which::FAILURE: return "Failure";
    case Which::FETCH_PHOTONS: return "FetchPhotons";
    case Which::FETCH_FILE: return "FetchFile";
    case Which::GOODBYE: return "Goodbye";
    case Which::SUBMIT: return "Submit";
    case Which::STATUS: return "Status";
    case Which::CANCEL: return "Cancel";
    case Which::PRIORITY: return "Priority";
    case Which::FETCH_IMAGE: return "FetchImage";
    case Which::JOB_DETAIL: return "JobDetail";
    case Which::FETCH_PREVIEW: return "FetchPreview";
    case Which::SHUTDOWN: return "Shutdown";
    default: return "this message";
  }
}
}  // namespace

std::optional<std::string> refusalFor(std::optional<net::Role> role, wire::Envelope::Which type) {
  if (!role) return fmt::format("{} refused: this connection was admitted in no role", nameOf(type));
  const bool allowed = *role == net::Role::Operator || (*role == net::Role::Worker && workerMay(type)) ||
                       (*role == net::Role::Client && clientMay(type));
  if (allowed) return std::nullopt;
  const std::string_view needs = workerMay(type) ? "a worker or operator key"
                                 : clientMay(type) ? "a client or operator key"
                                                   : "an operator key";
  return fmt::format("{} refused: a {} may not send it (it needs {})", nameOf(type), net::roleName(*role), needs);
}

}  // namespace portico
