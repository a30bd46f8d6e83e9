// SDO transfers (drivers/canopen/protocol/sdo*): the exact request and
// response bytes, a client and the simulated valve's server talking frame by
// frame (expedited and segmented uploads), every abort the server gives, the
// client's timeout, and responses that are not valid answers.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>

#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

using namespace rigctl::canopen;

namespace {

constexpr uint8_t kNode = 0x21;
constexpr int64_t kTimeout = 50'000'000;  // 50 ms
constexpr int64_t kT0 = 1'000'000'000;

std::array<OdEntry, 8> dictionary() {
  return {{
      {0x1000, 0, 4, Access::kReadOnly, 0x00010198},  // device type (CiA 408)
      {0x1001, 0, 1, Access::kReadOnly, 0x00},        // error register
      {0x1017, 0, 2, Access::kReadWrite, 0},          // producer heartbeat time
      {cia408::kControlWord, 0, 2, Access::kReadWrite, 0},
      {cia408::kDeviceMode, 0, 1, Access::kReadWrite, 0},
      {cia408::kSplSetpoint, 1, 2, Access::kReadWrite, 0},
      {cia408::kSplReferenceValue, 1, 2, Access::kReadOnly, 16384},
      {0x2100, 0, 3, Access::kWriteOnly, 0},          // a write-only 3-byte object
  }};
}

void expect_bytes(const CanFrame& f, uint32_t id, std::array<uint8_t, 8> bytes) {
  EXPECT_EQ(f.can_id, id);
  ASSERT_EQ(f.len, 8);
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], bytes[i]) << "byte " << i;
}

struct Pair {
  std::array<OdEntry, 8> od = dictionary();
  SdoServer server{kNode, od};
  SdoClient client{kNode, kTimeout};

  // Request -> server -> response -> client.
  SdoResult exchange(const std::optional<CanFrame>& request, int64_t now = kT0 + 1000) {
    EXPECT_TRUE(request.has_value());
    if (!request) return {};
    Malformed why = Malformed::kNone;
    const auto response = server.on_frame(*request, &why);
    EXPECT_EQ(why, Malformed::kNone);
    EXPECT_TRUE(response.has_value());
    if (!response) return {};
    EXPECT_EQ(response->can_id, 0x580U + kNode);
    return client.on_frame(*response, now);
  }
};

}  // namespace

// ---------------------------------------------------------------- frame bytes

TEST(SdoFrames, DownloadRequestCommandBytes) {
  expect_bytes(sdo_download_request(kNode, 0x6300, 1, 0xAB, 1), 0x621, {0x2F, 0x00, 0x63, 0x01, 0xAB, 0, 0, 0});
  expect_bytes(sdo_download_request(kNode, 0x6300, 1, 0xC000, 2), 0x621, {0x2B, 0x00, 0x63, 0x01, 0x00, 0xC0, 0, 0});
  expect_bytes(sdo_download_request(kNode, 0x2100, 0, 0x123456, 3), 0x621, {0x27, 0x00, 0x21, 0x00, 0x56, 0x34, 0x12, 0});
  expect_bytes(sdo_download_request(kNode, 0x1016, 1, 0x007F012C, 4), 0x621,
               {0x23, 0x16, 0x10, 0x01, 0x2C, 0x01, 0x7F, 0x00});
  expect_bytes(sdo_download_request(kNode, 0x1017, 0, 0x64, 0), 0x621, {0x22, 0x17, 0x10, 0x00, 0x64, 0, 0, 0});
  // Bytes beyond the size are not sent.
  expect_bytes(sdo_download_request(kNode, 0x6040, 0, 0xFFFF0007, 2), 0x621, {0x2B, 0x40, 0x60, 0x00, 0x07, 0, 0, 0});
}

TEST(SdoFrames, UploadRequestAndAbortBytes) {
  expect_bytes(sdo_upload_request(kNode, 0x6041, 0), 0x621, {0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0});
  expect_bytes(sdo_abort(0x5A1, 0x6300, 1, 0x06090011), 0x5A1, {0x80, 0x00, 0x63, 0x01, 0x11, 0x00, 0x09, 0x06});
}

TEST(SdoFrames, SignExtend) {
  EXPECT_EQ(sdo_sign_extend(0xFFFE, 2), -2);
  EXPECT_EQ(sdo_sign_extend(0x7FFF, 2), 32767);
  EXPECT_EQ(sdo_sign_extend(0x80, 1), -128);
  EXPECT_EQ(sdo_sign_extend(0xFFFFFF, 3), -1);
  EXPECT_EQ(sdo_sign_extend(0xFFFFFFFF, 4), -1);
  EXPECT_EQ(sdo_sign_extend(0x12345678, 0), 0x12345678);
}

TEST(SdoFrames, AbortCodeTexts) {
  EXPECT_STREQ(abort_code_text(0x05040000), "SDO protocol timed out");
  EXPECT_STREQ(abort_code_text(0x05040001), "client/server command specifier not valid or unknown");
  EXPECT_STREQ(abort_code_text(0x06010000), "unsupported access to an object");
  EXPECT_STREQ(abort_code_text(0x06010001), "attempt to read a write-only object");
  EXPECT_STREQ(abort_code_text(0x06010002), "attempt to write a read-only object");
  EXPECT_STREQ(abort_code_text(0x06020000), "object does not exist in the object dictionary");
  EXPECT_STREQ(abort_code_text(0x06090011), "sub-index does not exist");
  EXPECT_STREQ(abort_code_text(0x06070010), "data type does not match, length of service parameter does not match");
  EXPECT_STREQ(abort_code_text(0x06090030), "invalid value for parameter");
  EXPECT_STREQ(abort_code_text(0x08000000), "general error");
  EXPECT_STREQ(abort_code_text(0x08000022),
               "data cannot be transferred or stored to the application because of the present device state");
  EXPECT_STREQ(abort_code_text(0x12345678), "unknown abort code");
}

// ---------------------------------------------------------------- client <-> server

TEST(SdoTransfer, DownloadOneTwoThreeFourBytes) {
  Pair p;
  SdoResult r = p.exchange(p.client.start_download(cia408::kDeviceMode, 0, 1, 1, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(p.server.find(cia408::kDeviceMode, 0)->value, 1U);

  r = p.exchange(p.client.start_download(cia408::kSplSetpoint, 1, 0xE000, 2, kT0));  // -8192
  EXPECT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.index, cia408::kSplSetpoint);
  EXPECT_EQ(r.subindex, 1);
  EXPECT_EQ(sdo_sign_extend(p.server.find(cia408::kSplSetpoint, 1)->value, 2), -8192);

  r = p.exchange(p.client.start_download(0x2100, 0, 0xABCDEF, 3, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(p.server.find(0x2100, 0)->value, 0xABCDEFU);

  // 4 bytes into a 2-byte object: size indicated and wrong -> abort (below);
  // into the 2-byte heartbeat time with size not indicated: accepted, truncated to the object.
  r = p.exchange(p.client.start_download(0x1017, 0, 0x000100C8, 0, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(p.server.find(0x1017, 0)->value, 0x00C8U);
  EXPECT_EQ(p.server.writes(), 4U);
  EXPECT_FALSE(p.client.busy());
}

TEST(SdoTransfer, UploadOneTwoFourBytes) {
  Pair p;
  SdoResult r = p.exchange(p.client.start_upload(0x1001, 0, kT0));
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 1);
  EXPECT_EQ(r.value, 0U);

  r = p.exchange(p.client.start_upload(cia408::kSplReferenceValue, 1, kT0));
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 2);
  EXPECT_EQ(r.value, 16384U);

  r = p.exchange(p.client.start_upload(0x1000, 0, kT0));
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 4);
  EXPECT_EQ(r.value, 0x00010198U);
}

TEST(SdoTransfer, UploadResponseBytesFromServer) {
  std::array<OdEntry, 8> od = dictionary();
  SdoServer server(kNode, od);
  auto resp = server.on_frame(sdo_upload_request(kNode, 0x1001, 0));
  ASSERT_TRUE(resp);
  expect_bytes(*resp, 0x5A1, {0x4F, 0x01, 0x10, 0x00, 0x00, 0, 0, 0});
  resp = server.on_frame(sdo_upload_request(kNode, cia408::kSplReferenceValue, 1));
  ASSERT_TRUE(resp);
  expect_bytes(*resp, 0x5A1, {0x4B, 0x11, 0x63, 0x01, 0x00, 0x40, 0, 0});
  resp = server.on_frame(sdo_upload_request(kNode, 0x1000, 0));
  ASSERT_TRUE(resp);
  expect_bytes(*resp, 0x5A1, {0x43, 0x00, 0x10, 0x00, 0x98, 0x01, 0x01, 0x00});
  resp = server.on_frame(sdo_download_request(kNode, 0x6040, 0, 7, 2));
  ASSERT_TRUE(resp);
  expect_bytes(*resp, 0x5A1, {0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0});
}

TEST(SdoTransfer, ClientUploadOfThreeBytesAndUnsizedResponse) {
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x2200, 0, kT0));
  SdoResult r = c.on_frame(make_frame(0x5A1, {0x47, 0x00, 0x22, 0x00, 1, 2, 3, 0xEE}), kT0 + 1);
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 3);
  EXPECT_EQ(r.value, 0x030201U);  // the unused fourth byte is dropped
  ASSERT_TRUE(c.start_upload(0x2200, 0, kT0));
  r = c.on_frame(make_frame(0x5A1, {0x42, 0x00, 0x22, 0x00, 1, 2, 3, 4}), kT0 + 1);
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 0);
  EXPECT_EQ(r.value, 0x04030201U);
}

// ---------------------------------------------------------------- server aborts

TEST(SdoServerAborts, EveryCase) {
  struct Case {
    const char* what;
    CanFrame request;
    uint32_t code;
  };
  const Case cases[] = {
      {"unknown index", sdo_upload_request(kNode, 0x6500, 0), 0x06020000},
      {"unknown index (write)", sdo_download_request(kNode, 0x6500, 0, 1, 1), 0x06020000},
      {"unknown subindex", sdo_upload_request(kNode, cia408::kSplSetpoint, 2), 0x06090011},
      {"unknown subindex (write)", sdo_download_request(kNode, 0x1017, 1, 1, 2), 0x06090011},
      {"write read-only", sdo_download_request(kNode, cia408::kSplReferenceValue, 1, 1, 2), 0x06010002},
      {"read write-only", sdo_upload_request(kNode, 0x2100, 0), 0x06010001},
      {"size too big", sdo_download_request(kNode, 0x1017, 0, 100, 4), 0x06070010},
      {"size too small", sdo_download_request(kNode, 0x1017, 0, 100, 1), 0x06070010},
      {"segmented download", make_frame(0x621, {0x21, 0x17, 0x10, 0x00, 8, 0, 0, 0}), 0x05040001},
      {"segment request", make_frame(0x621, {0x00, 0, 0, 0, 0, 0, 0, 0}), 0x05040001},
      {"upload segment", make_frame(0x621, {0x60, 0, 0, 0, 0, 0, 0, 0}), 0x05040001},
      {"block command", make_frame(0x621, {0xC0, 0x17, 0x10, 0, 0, 0, 0, 0}), 0x05040001},
      {"command 7", make_frame(0x621, {0xE0, 0x17, 0x10, 0, 0, 0, 0, 0}), 0x05040001},
  };
  for (const auto& c : cases) {
    std::array<OdEntry, 8> od = dictionary();
    const std::array<OdEntry, 8> before = od;
    SdoServer server(kNode, od);
    const auto resp = server.on_frame(c.request);
    ASSERT_TRUE(resp) << c.what;
    EXPECT_EQ(resp->can_id, 0x5A1U) << c.what;
    EXPECT_EQ(resp->data[0], 0x80) << c.what;
    EXPECT_EQ(resp->data[1], c.request.data[1]) << c.what;  // multiplexer echoed
    EXPECT_EQ(resp->data[2], c.request.data[2]) << c.what;
    EXPECT_EQ(resp->data[3], c.request.data[3]) << c.what;
    EXPECT_EQ(get_u32le(&resp->data[4]), c.code) << c.what;
    EXPECT_EQ(server.writes(), 0U) << c.what;
    for (std::size_t i = 0; i < od.size(); ++i) EXPECT_EQ(od[i].value, before[i].value) << c.what;
  }
}

TEST(SdoServerAborts, ClientSeesAbortCodeAndText) {
  Pair p;
  SdoResult r = p.exchange(p.client.start_upload(0x6500, 0, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x06020000U);
  EXPECT_STREQ(r.text, "object does not exist in the object dictionary");
  EXPECT_FALSE(r.to_send.has_value());  // the server aborted: nothing to send back
  EXPECT_FALSE(p.client.busy());

  r = p.exchange(p.client.start_download(cia408::kSplReferenceValue, 1, 0, 2, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x06010002U);
  r = p.exchange(p.client.start_download(cia408::kControlWord, 0, 7, 1, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x06070010U);
  r = p.exchange(p.client.start_upload(cia408::kSplSetpoint, 9, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x06090011U);
}

TEST(SdoServerAborts, OversizeEntryIsUnsupportedAccess) {
  std::array<OdEntry, 1> od{{{0x1008, 0, 12, Access::kReadOnly, 0}}};  // e.g. a VISIBLE_STRING
  SdoServer server(kNode, od);
  const auto resp = server.on_frame(sdo_upload_request(kNode, 0x1008, 0));
  ASSERT_TRUE(resp);
  EXPECT_EQ(resp->data[0], 0x80);
  EXPECT_EQ(get_u32le(&resp->data[4]), 0x06010000U);
}

TEST(SdoServerAborts, IgnoresWhatIsNotARequestForIt) {
  std::array<OdEntry, 8> od = dictionary();
  SdoServer server(kNode, od);
  Malformed why = Malformed::kBadContent;
  EXPECT_FALSE(server.on_frame(sdo_upload_request(kNode + 1, 0x1000, 0), &why));  // other node
  EXPECT_EQ(why, Malformed::kNone);
  EXPECT_FALSE(server.on_frame(make_frame(0x5A1, {0x40, 0, 0x10, 0, 0, 0, 0, 0}), &why));  // a response id
  EXPECT_FALSE(server.on_frame(sdo_abort(0x621, 0x1000, 0, 0x05040000), &why));  // client abort: no answer
  EXPECT_EQ(why, Malformed::kNone);
  EXPECT_FALSE(server.on_frame(make_frame(0x621, {0x40, 0x00, 0x10, 0x00}), &why));
  EXPECT_EQ(why, Malformed::kWrongLength);
  CanFrame rtr = sdo_upload_request(kNode, 0x1000, 0);
  rtr.can_id |= kCanRtrFlag;
  EXPECT_FALSE(server.on_frame(rtr, &why));
}

// ---------------------------------------------------------------- client timeout

TEST(SdoClientTimeout, AbortsWithTimeoutCodeAfterTheDeadline) {
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x1000, 0, kT0));
  EXPECT_EQ(c.poll(kT0).kind, SdoResult::Kind::kPending);
  EXPECT_EQ(c.poll(kT0 + kTimeout).kind, SdoResult::Kind::kPending);  // at the deadline: still in time
  EXPECT_TRUE(c.busy());
  const SdoResult r = c.poll(kT0 + kTimeout + 1);
  ASSERT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x05040000U);
  EXPECT_STREQ(r.text, "SDO protocol timed out");
  EXPECT_EQ(r.index, 0x1000);
  ASSERT_TRUE(r.to_send.has_value());
  expect_bytes(*r.to_send, 0x621, {0x80, 0x00, 0x10, 0x00, 0x00, 0x00, 0x04, 0x05});
  EXPECT_FALSE(c.busy());
  EXPECT_EQ(c.poll(kT0 + 10 * kTimeout).kind, SdoResult::Kind::kPending);  // reported once

  // The server's answer arriving now is unexpected.
  const SdoResult late = c.on_frame(make_frame(0x5A1, {0x43, 0x00, 0x10, 0x00, 1, 2, 3, 4}), kT0 + kTimeout + 2);
  EXPECT_EQ(late.kind, SdoResult::Kind::kMalformed);
  EXPECT_EQ(late.malformed, Malformed::kUnexpectedSdo);
}

TEST(SdoClientTimeout, ResponseAtTheDeadlineIsInTimeOneLaterIsNot) {
  SdoClient c(kNode, kTimeout);
  const CanFrame answer = make_frame(0x5A1, {0x60, 0x17, 0x10, 0x00, 0, 0, 0, 0});
  ASSERT_TRUE(c.start_download(0x1017, 0, 100, 2, kT0));
  EXPECT_EQ(c.on_frame(answer, kT0 + kTimeout).kind, SdoResult::Kind::kDone);

  ASSERT_TRUE(c.start_download(0x1017, 0, 100, 2, kT0));
  const SdoResult r = c.on_frame(answer, kT0 + kTimeout + 1);  // no poll() in between
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x05040000U);
  EXPECT_FALSE(c.busy());
}

// ---------------------------------------------------------------- bad responses

TEST(SdoClientProtocol, UnexpectedResponsesAreProtocolErrors) {
  struct Case {
    const char* what;
    bool upload;
    CanFrame response;
    uint32_t abort_we_send;
  };
  // Pending: download or upload of 0x6300 sub 1.
  const Case cases[] = {
      {"upload response to a download", false, make_frame(0x5A1, {0x4B, 0x00, 0x63, 0x01, 0, 0, 0, 0}), 0x05040001},
      {"download segment response, toggle set", false, make_frame(0x5A1, {0x30, 0x00, 0x63, 0x01, 0, 0, 0, 0}),
       0x05040001},
      {"toggle bit set in download response", false, make_frame(0x5A1, {0x70, 0x00, 0x63, 0x01, 0, 0, 0, 0}),
       0x05040001},
      {"download response to an upload", true, make_frame(0x5A1, {0x60, 0x00, 0x63, 0x01, 0, 0, 0, 0}), 0x05040001},
      {"toggle bit set in upload response", true, make_frame(0x5A1, {0x53, 0x00, 0x63, 0x01, 0, 0, 0, 0}),
       0x05040001},
      {"upload segment", true, make_frame(0x5A1, {0x00, 1, 2, 3, 4, 5, 6, 7}), 0x05040001},
  };
  for (const auto& c : cases) {
    SdoClient client(kNode, kTimeout);
    ASSERT_TRUE(c.upload ? client.start_upload(0x6300, 1, kT0) : client.start_download(0x6300, 1, 5, 2, kT0));
    const SdoResult r = client.on_frame(c.response, kT0 + 1);
    EXPECT_EQ(r.kind, SdoResult::Kind::kProtocolError) << c.what;
    EXPECT_GT(std::string(r.text).size(), 0U) << c.what;
    EXPECT_FALSE(client.busy()) << c.what;
    ASSERT_TRUE(r.to_send.has_value()) << c.what;
    EXPECT_EQ(r.to_send->can_id, 0x621U) << c.what;
    EXPECT_EQ(r.to_send->data[0], 0x80) << c.what;
    EXPECT_EQ(get_u16le(&r.to_send->data[1]), 0x6300) << c.what;
    EXPECT_EQ(r.to_send->data[3], 1) << c.what;
    EXPECT_EQ(get_u32le(&r.to_send->data[4]), c.abort_we_send) << c.what;
  }
}

// An answer for another object is a late answer to an earlier request (one
// that timed out and was sent again): dropped, and the transfer waits on
// for its own answer.
TEST(SdoClientProtocol, AnswerForAnotherObjectIsDroppedAndTheTransferGoesOn) {
  struct Case {
    const char* what;
    bool upload;
    CanFrame stale;
    CanFrame own;
  };
  const Case cases[] = {
      {"download, wrong index", false, make_frame(0x5A1, {0x60, 0x01, 0x63, 0x01, 0, 0, 0, 0}),
       make_frame(0x5A1, {0x60, 0x00, 0x63, 0x01, 0, 0, 0, 0})},
      {"download, wrong subindex", false, make_frame(0x5A1, {0x60, 0x00, 0x63, 0x02, 0, 0, 0, 0}),
       make_frame(0x5A1, {0x60, 0x00, 0x63, 0x01, 0, 0, 0, 0})},
      {"upload, the previous object's answer", true, make_frame(0x5A1, {0x43, 0x00, 0x10, 0x00, 0x98, 0x01, 0, 0}),
       make_frame(0x5A1, {0x4B, 0x00, 0x63, 0x01, 0x34, 0x12, 0, 0})},
  };
  for (const auto& c : cases) {
    SdoClient client(kNode, kTimeout);
    ASSERT_TRUE(c.upload ? client.start_upload(0x6300, 1, kT0) : client.start_download(0x6300, 1, 5, 2, kT0));
    const SdoResult stale = client.on_frame(c.stale, kT0 + 1);
    EXPECT_EQ(stale.kind, SdoResult::Kind::kMalformed) << c.what;
    EXPECT_EQ(stale.malformed, Malformed::kUnexpectedSdo) << c.what;
    EXPECT_FALSE(stale.to_send.has_value()) << c.what << ": nothing aborted";
    EXPECT_TRUE(client.busy()) << c.what;
    const SdoResult own = client.on_frame(c.own, kT0 + 2);
    EXPECT_EQ(own.kind, SdoResult::Kind::kDone) << c.what;
    if (c.upload) {
      EXPECT_EQ(own.value, 0x1234U) << c.what;
    }
  }
}

TEST(SdoClientProtocol, AbortIsAcceptedWhateverItEchoes) {
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x6300, 1, kT0));
  const SdoResult r = c.on_frame(sdo_abort(0x5A1, 0, 0, 0x08000022), kT0 + 1);
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x08000022U);
  EXPECT_EQ(r.index, 0x6300);  // the transfer's, not the echo's
}

TEST(SdoClientProtocol, MalformedAndForeignFrames) {
  SdoClient c(kNode, kTimeout);
  // Nothing pending: a response is unexpected.
  SdoResult r = c.on_frame(make_frame(0x5A1, {0x60, 0, 0x63, 1, 0, 0, 0, 0}), kT0);
  EXPECT_EQ(r.kind, SdoResult::Kind::kMalformed);
  EXPECT_EQ(r.malformed, Malformed::kUnexpectedSdo);

  ASSERT_TRUE(c.start_download(0x6300, 1, 5, 2, kT0));
  // Another node's SDO response, a heartbeat: not ours, the transfer goes on.
  EXPECT_EQ(c.on_frame(make_frame(0x5A2, {0x60, 0, 0x63, 1, 0, 0, 0, 0}), kT0 + 1).kind, SdoResult::Kind::kIgnored);
  EXPECT_EQ(c.on_frame(make_frame(0x721, {0x05}), kT0 + 1).kind, SdoResult::Kind::kIgnored);
  CanFrame eff = make_frame(0x5A1, {0x60, 0, 0x63, 1, 0, 0, 0, 0});
  eff.can_id |= kCanEffFlag;
  EXPECT_EQ(c.on_frame(eff, kT0 + 1).kind, SdoResult::Kind::kIgnored);
  // Wrong length: dropped, counted by the caller, transfer still pending.
  r = c.on_frame(make_frame(0x5A1, {0x60, 0x00, 0x63, 0x01}), kT0 + 1);
  EXPECT_EQ(r.kind, SdoResult::Kind::kMalformed);
  EXPECT_EQ(r.malformed, Malformed::kWrongLength);
  EXPECT_TRUE(c.busy());
  // Then the real answer completes it.
  EXPECT_EQ(c.on_frame(make_frame(0x5A1, {0x60, 0x00, 0x63, 0x01, 0, 0, 0, 0}), kT0 + 2).kind,
            SdoResult::Kind::kDone);
}

TEST(SdoClientProtocol, OneTransferAtATime) {
  SdoClient c(kNode, kTimeout);
  EXPECT_FALSE(c.start_download(0x6300, 1, 0, 5, kT0).has_value());  // size > 4
  EXPECT_FALSE(c.busy());
  ASSERT_TRUE(c.start_upload(0x6300, 1, kT0));
  EXPECT_FALSE(c.start_upload(0x6301, 1, kT0).has_value());
  EXPECT_FALSE(c.start_download(0x6300, 1, 0, 2, kT0).has_value());
  c.cancel();
  EXPECT_FALSE(c.busy());
  EXPECT_TRUE(c.start_upload(0x6301, 1, kT0).has_value());
  EXPECT_EQ(c.request_cob_id(), 0x621U);
  EXPECT_EQ(c.response_cob_id(), 0x5A1U);
}

// A start-up sequence as the driver will run it, frame by frame.
TEST(SdoTransfer, ConfigurationSequence) {
  Pair p;
  struct Step {
    uint16_t index;
    uint8_t sub;
    uint32_t value;
    uint8_t size;
  };
  const Step steps[] = {{0x1017, 0, 100, 2},
                        {cia408::kDeviceMode, 0, static_cast<uint8_t>(cia408::kDeviceModeBus), 1},
                        {cia408::kControlWord, 0, cia408::kControlActive, 2}};
  int64_t now = kT0;
  for (const auto& s : steps) {
    const SdoResult r = p.exchange(p.client.start_download(s.index, s.sub, s.value, s.size, now), now + 100'000);
    EXPECT_EQ(r.kind, SdoResult::Kind::kDone) << std::hex << s.index;
    now += 1'000'000;
  }
  const SdoResult r = p.exchange(p.client.start_upload(cia408::kControlWord, 0, now), now + 1);
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.value, cia408::kControlActive);
  EXPECT_EQ(p.server.find(cia408::kDeviceMode, 0)->value, 1U);
}

// ---------------------------------------------------------------- segmented upload

namespace {
// The server's answer to the segment request the client asked for.
CanFrame segment(uint8_t command, std::initializer_list<uint8_t> data) {
  CanFrame f = make_frame(0x5A1, {command, 0, 0, 0, 0, 0, 0, 0});
  uint8_t i = 1;
  for (uint8_t b : data) f.data[i++] = b;
  return f;
}
}  // namespace

TEST(SdoSegmentedUpload, TenBytesInTwoSegmentsWithTheToggleAlternating) {
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x1008, 0, kT0));
  // Initiate response: segmented, size indicated (10 bytes).
  SdoResult r = c.on_frame(make_frame(0x5A1, {0x41, 0x08, 0x10, 0x00, 10, 0, 0, 0}), kT0 + 1);
  ASSERT_EQ(r.kind, SdoResult::Kind::kPending);
  ASSERT_TRUE(r.to_send.has_value());
  expect_bytes(*r.to_send, 0x621, {0x60, 0, 0, 0, 0, 0, 0, 0});  // first segment request, toggle 0
  // 7 bytes, toggle 0, more to come.
  r = c.on_frame(segment(0x00, {'r', 'i', 'g', 'c', 't', 'l', ' '}), kT0 + 2);
  ASSERT_EQ(r.kind, SdoResult::Kind::kPending);
  ASSERT_TRUE(r.to_send.has_value());
  expect_bytes(*r.to_send, 0x621, {0x70, 0, 0, 0, 0, 0, 0, 0});  // toggle 1
  // 3 bytes (n = 4), toggle 1, last.
  r = c.on_frame(segment(0x10 | (4 << 1) | 1, {'v', 'l', 'v'}), kT0 + 3);
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_TRUE(r.segmented);
  EXPECT_EQ(r.size, 10);
  EXPECT_EQ(std::string(r.bytes.begin(), r.bytes.begin() + r.size), "rigctl vlv");
  EXPECT_EQ(r.value, 0x63676972U);  // the first four bytes, little-endian
  EXPECT_FALSE(c.busy());
}

TEST(SdoSegmentedUpload, EachSegmentHasItsOwnTimeout) {
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x1008, 0, kT0));
  ASSERT_EQ(c.on_frame(make_frame(0x5A1, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}), kT0 + kTimeout).kind,
            SdoResult::Kind::kPending);
  // Twice the timeout after the transfer began, within one of the request.
  const SdoResult r = c.on_frame(segment(0x00 | (5 << 1) | 1, {0x34, 0x12}), kT0 + 2 * kTimeout);
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(r.size, 2);  // size not indicated: what came
  EXPECT_EQ(r.value, 0x1234U);
  ASSERT_TRUE(c.start_upload(0x1008, 0, kT0));
  ASSERT_EQ(c.on_frame(make_frame(0x5A1, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}), kT0 + 1).kind, SdoResult::Kind::kPending);
  const SdoResult late = c.poll(kT0 + 1 + kTimeout + 1);
  EXPECT_EQ(late.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(late.abort_code, 0x05040000U);
}

TEST(SdoSegmentedUpload, BadSegmentsAbortWithTheirCodes) {
  struct Case {
    const char* what;
    uint8_t initiate;
    uint32_t announced;
    CanFrame segment;
    uint32_t abort;
  };
  const Case cases[] = {
      {"toggle not alternated", 0x41, 4, segment(0x10 | (3 << 1) | 1, {1, 2, 3, 4}), 0x05030000},
      {"fewer bytes than announced", 0x41, 4, segment(0x00 | (5 << 1) | 1, {1, 2}), 0x06070010},
      {"not a segment response", 0x41, 4, segment(0x60, {1, 2, 3, 4, 5, 6, 7}), 0x05040001},
      {"announced more than the client takes", 0x41, 65, segment(0x01, {}), 0x05040005},
  };
  for (const auto& k : cases) {
    SdoClient c(kNode, kTimeout);
    ASSERT_TRUE(c.start_upload(0x1008, 0, kT0));
    SdoResult r = c.on_frame(make_frame(0x5A1, {k.initiate, 0x08, 0x10, 0x00, static_cast<uint8_t>(k.announced), 0, 0, 0}),
                             kT0 + 1);
    if (r.kind == SdoResult::Kind::kPending) r = c.on_frame(k.segment, kT0 + 2);
    EXPECT_EQ(r.kind, SdoResult::Kind::kProtocolError) << k.what;
    EXPECT_EQ(r.abort_code, k.abort) << k.what;
    ASSERT_TRUE(r.to_send.has_value()) << k.what;
    EXPECT_EQ(get_u32le(&r.to_send->data[4]), k.abort) << k.what;
    EXPECT_FALSE(c.busy()) << k.what;
  }
  // Nine segments of 7 bytes and one more: beyond the client's 64 bytes.
  SdoClient c(kNode, kTimeout);
  ASSERT_TRUE(c.start_upload(0x1008, 0, kT0));
  SdoResult r = c.on_frame(make_frame(0x5A1, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}), kT0 + 1);
  for (int i = 0; i < 10 && r.kind == SdoResult::Kind::kPending; ++i) {
    r = c.on_frame(segment(static_cast<uint8_t>(i % 2 ? 0x10 : 0x00), {1, 2, 3, 4, 5, 6, 7}), kT0 + 2 + i);
  }
  EXPECT_EQ(r.kind, SdoResult::Kind::kProtocolError);
  EXPECT_EQ(r.abort_code, 0x05040005U);
}

TEST(SdoSegmentedUpload, ServerAnswersSegmentedWhenAskedAndTheClientTakesIt) {
  Pair p;
  p.server.set_segmented_uploads(true);
  const auto request = p.client.start_upload(0x1000, 0, kT0);
  ASSERT_TRUE(request);
  auto response = p.server.on_frame(*request);
  ASSERT_TRUE(response);
  expect_bytes(*response, 0x5A1, {0x41, 0x00, 0x10, 0x00, 4, 0, 0, 0});
  SdoResult r = p.client.on_frame(*response, kT0 + 1);
  int segments = 0;
  while (r.kind == SdoResult::Kind::kPending && segments < 10) {
    ASSERT_TRUE(r.to_send);
    response = p.server.on_frame(*r.to_send);
    ASSERT_TRUE(response);
    r = p.client.on_frame(*response, kT0 + 2);
    ++segments;
  }
  ASSERT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(segments, 1);
  EXPECT_TRUE(r.segmented);
  EXPECT_EQ(r.value, 0x00010198U);
  EXPECT_EQ(r.size, 4);
  // A segment request with no segmented upload pending is refused.
  const auto stray = p.server.on_frame(make_frame(0x621, {0x60, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(stray);
  EXPECT_EQ(get_u32le(&stray->data[4]), 0x05040001U);
}

TEST(SdoServerWriteCheck, RefusalIsTheAbortCodeAndTheValueStays) {
  Pair p;
  p.server.set_write_check([](const OdEntry& e, uint32_t value) -> uint32_t {
    return e.index == cia408::kDeviceMode && value > 1 ? 0x06090031 : 0;  // value too high
  });
  SdoResult r = p.exchange(p.client.start_download(cia408::kDeviceMode, 0, 2, 1, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kAbort);
  EXPECT_EQ(r.abort_code, 0x06090031U);
  EXPECT_EQ(p.server.find(cia408::kDeviceMode, 0)->value, 0U);
  EXPECT_EQ(p.server.writes(), 0U);
  r = p.exchange(p.client.start_download(cia408::kDeviceMode, 0, 1, 1, kT0));
  EXPECT_EQ(r.kind, SdoResult::Kind::kDone);
  EXPECT_EQ(p.server.find(cia408::kDeviceMode, 0)->value, 1U);
}
