// What each role may send the coordinator (coordinator/peer_rights.h).
#include "coordinator/peer_rights.h"

#include <gtest/gtest.h>

namespace portico {
namespace {

using Which = wire::Envelope::Which;
using net::Role;

TEST(PeerRights, WorkersLeaseAndFetchButNeitherSubmitNorShutDown) {
  for (Which type : {Which::HELLO, Which::READY, Which::HEARTBEAT, Which::RESULT, Which::FAILURE, Which::FETCH_PHOTONS,
                     Which::FETCH_FILE, Which::GOODBYE})
    EXPECT_FALSE(refusalFor(Role::Worker, type)) << int(type);
  for (Which type : {Which::SUBMIT, Which::STATUS, Which::CANCEL, Which::PRIORITY, Which::FETCH_IMAGE, Which::SHUTDOWN})
    EXPECT_TRUE(refusalFor(Role::Worker, type)) << int(type);
  EXPECT_EQ(refusalFor(Role::Worker, Which::PRIORITY).value_or(""),
            "Priority refused: a worker may not send it (it needs a client or operator key)");
  EXPECT_EQ(refusalFor(Role::Worker, Which::SUBMIT).value_or(""),
            "Submit refused: a worker may not send it (it needs a client or operator key)");
  // The dashboard's requests are a client's.
  EXPECT_EQ(refusalFor(Role::Worker, Which::FETCH_PREVIEW).value_or(""),
            "FetchPreview refused: a worker may not send it (it needs a client or operator key)");
  EXPECT_EQ(refusalFor(Role::Worker, Which::JOB_DETAIL).value_or(""),
            "JobDetail refused: a worker may not send it (it needs a client or operator key)");
  EXPECT_EQ(refusalFor(Role::Worker, Which::SHUTDOWN).value_or(""),
            "Shutdown refused: a worker may not send it (it needs an operator key)");
}

TEST(PeerRights, ClientsAskAboutJobsButNeitherLeaseNorFetchFilesNorShutDown) {
  for (Which type : {Which::SUBMIT, Which::STATUS, Which::CANCEL, Which::PRIORITY, Which::FETCH_IMAGE, Which::JOB_DETAIL,
                     Which::FETCH_PREVIEW})
    EXPECT_FALSE(refusalFor(Role::Client, type)) << int(type);
  for (Which type : {Which::HELLO, Which::READY, Which::RESULT, Which::FAILURE, Which::FETCH_PHOTONS, Which::FETCH_FILE,
                     Which::SHUTDOWN})
    EXPECT_TRUE(refusalFor(Role::Client, type)) << int(type);
  EXPECT_EQ(refusalFor(Role::Client, Which::FETCH_FILE).value_or(""),
            "FetchFile refused: a client may not send it (it needs a worker or operator key)");
}

TEST(PeerRights, OperatorsMaySendAnythingAndPeersWithoutARoleNothing) {
  for (Which type :
       {Which::HELLO, Which::RESULT, Which::FETCH_FILE, Which::SUBMIT, Which::CANCEL, Which::PRIORITY, Which::SHUTDOWN}) {
    EXPECT_FALSE(refusalFor(Role::Operator, type)) << int(type);
    EXPECT_TRUE(refusalFor(std::nullopt, type)) << int(type);
  }
}

}  // namespace
}  // namespace portico
