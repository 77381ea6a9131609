// The Foxglove WebSocket protocol without the network: frames byte by byte as the spec lays them
// out, and a client session's answers to good, bad and unknown requests.
#include <gtest/gtest.h>

#include "common/foxglove_protocol.hpp"
#include "common/foxglove_schemas.hpp"

namespace polarslam::foxglove {
namespace {

using Json = nlohmann::json;

ChannelTable twoChannels() {
  ChannelTable table;
  table.add("LASER", "foxglove.LaserScan");
  table.add("GRID_MAP", "foxglove.Grid");
  return table;
}

std::string clientData(uint32_t channel, const std::string& payload) {
  std::string frame(1, '\x01');
  for (int i = 0; i < 4; ++i) frame += static_cast<char>((channel >> (8 * i)) & 0xff);
  return frame + payload;
}

TEST(FoxgloveProtocol, AdvertiseListsEveryChannelWithItsJsonSchema) {
  const ChannelTable table = twoChannels();
  EXPECT_EQ(table.find("GRID_MAP"), 2u);
  EXPECT_FALSE(table.find("NOPE"));
  EXPECT_THROW(ChannelTable().add("X", "foxglove.Unknown"), std::invalid_argument);
  const Json advertise = Json::parse(table.advertiseMessage());
  EXPECT_EQ(advertise["op"], "advertise");
  ASSERT_EQ(advertise["channels"].size(), 2u);
  const Json& grid = advertise["channels"][1];
  EXPECT_EQ(grid["id"], 2);
  EXPECT_EQ(grid["topic"], "GRID_MAP");
  EXPECT_EQ(grid["encoding"], "json");
  EXPECT_EQ(grid["schemaName"], "foxglove.Grid");
  EXPECT_EQ(grid["schemaEncoding"], "jsonschema");
  EXPECT_EQ(Json::parse(grid["schema"].get<std::string>()), schema("foxglove.Grid"));
}

TEST(FoxgloveProtocol, ServerInfoAndStatus) {
  const Json info = Json::parse(serverInfoMessage("polarslam-bridge", {"clientPublish"}, {{"goal_topic", "GOAL"}}));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"][0], "clientPublish");
  EXPECT_EQ(info["supportedEncodings"][0], "json");
  EXPECT_EQ(info["metadata"]["goal_topic"], "GOAL");
  const Json status = Json::parse(statusMessage(StatusLevel::Error, "bad"));
  EXPECT_EQ(status["op"], "status");
  EXPECT_EQ(status["level"], 2);
}

TEST(FoxgloveProtocol, MessageDataFrameIsOpcodeSubscriptionTimeLittleEndianThenPayload) {
  const std::string frame = messageDataFrame(0x01020304u, 0x1122334455667788ull, "{}");
  const std::string expected("\x01\x04\x03\x02\x01\x88\x77\x66\x55\x44\x33\x22\x11{}", 15);
  EXPECT_EQ(frame, expected);
}

TEST(FoxgloveProtocol, SubscribeAndUnsubscribe) {
  const ChannelTable table = twoChannels();
  ClientSession session(table, {});
  auto out = session.onText(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":2},{"id":8,"channelId":1}]})");
  EXPECT_TRUE(out.replies.empty());
  EXPECT_EQ(session.subscriptionFor(2), 7u);
  EXPECT_EQ(session.subscriptionFor(1), 8u);
  out = session.onText(R"({"op":"unsubscribe","subscriptionIds":[7]})");
  EXPECT_TRUE(out.errors.empty());
  EXPECT_FALSE(session.subscriptionFor(2));
  EXPECT_EQ(session.subscriptionFor(1), 8u);
}

TEST(FoxgloveProtocol, BadRequestsGetAnErrorStatusAndAReason) {
  const ChannelTable table = twoChannels();
  ClientSession session(table, {});
  session.onText(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  const std::vector<std::string> bad = {
      "not json",
      R"({"op":"subscribe","subscriptions":[{"id":1e999,"channelId":1}]})",
      "[1,2]",
      R"({"noop":1})",
      R"({"op":"getParameters","parameterNames":[]})",
      R"({"op":"subscribe"})",
      R"({"op":"subscribe","subscriptions":[{"id":2,"channelId":99}]})",
      R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":2}]})",
      R"({"op":"subscribe","subscriptions":[{"id":3,"channelId":1}]})",
      R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
      R"({"op":"subscribe","subscriptions":[{"id":"x","channelId":1}]})",
      R"({"op":"unsubscribe","subscriptionIds":[42]})",
      R"({"op":"unsubscribe","subscriptionIds":"all"})",
      R"({"op":"advertise","channels":[{"id":1,"topic":"GOAL","encoding":"json","schemaName":"g"}]})",
  };
  for (const std::string& text : bad) {
    const auto out = session.onText(text);
    ASSERT_EQ(out.replies.size(), 1u) << text;
    EXPECT_EQ(out.errors.size(), 1u) << text;
    const Json status = Json::parse(out.replies[0]);
    EXPECT_EQ(status["op"], "status") << text;
    EXPECT_EQ(status["level"], 2) << text;
  }
  EXPECT_EQ(session.subscriptionFor(1), 1u);  // nothing above changed the good subscription
  EXPECT_FALSE(session.subscriptionFor(2));
  for (const std::string& binary : {std::string(), std::string("\x02\x00\x00\x00\x00", 5), clientData(1, "{}")})
    EXPECT_EQ(session.onBinary(binary).errors.size(), 1u);
}

TEST(FoxgloveProtocol, ClientsPublishOnlyOnAllowedTopicsAfterAdvertising) {
  const ChannelTable table = twoChannels();
  ClientSession session(table, {"GOAL"});
  EXPECT_EQ(session.onBinary(clientData(5, R"({"x":1,"y":2})")).errors.size(), 1u);  // not advertised yet
  auto out = session.onText(R"({"op":"advertise","channels":[{"id":5,"topic":"GOAL","encoding":"json","schemaName":"g"},
                                                             {"id":6,"topic":"LASER","encoding":"json","schemaName":"s"},
                                                             {"id":7,"topic":"GOAL","encoding":"cdr","schemaName":"g"}]})");
  EXPECT_EQ(out.errors.size(), 2u);  // LASER is not publishable, cdr is not json
  out = session.onBinary(clientData(5, R"({"x":1,"y":2})"));
  ASSERT_EQ(out.publications.size(), 1u);
  EXPECT_EQ(out.publications[0].topic, "GOAL");
  EXPECT_EQ(out.publications[0].payload["y"], 2);
  EXPECT_EQ(session.onBinary(clientData(5, "{broken")).errors.size(), 1u);
  EXPECT_EQ(session.onBinary(clientData(5, R"({"x":1e999,"y":0})")).errors.size(), 1u);  // overflows a double
  EXPECT_TRUE(session.onText(R"({"op":"unadvertise","channelIds":[5]})").errors.empty());
  EXPECT_EQ(session.onBinary(clientData(5, R"({"x":1,"y":2})")).errors.size(), 1u);
}

TEST(FrameQueue, KeepsTheNewestAndCountsTheDropped) {
  FrameQueue queue(3);
  size_t dropped = 0;
  for (const char* frame : {"1", "2", "3", "4", "5"}) dropped += queue.push(frame);
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(queue.dropped(), 2u);
  ASSERT_EQ(queue.size(), 3u);
  EXPECT_EQ(queue.pop(), "3");
  EXPECT_EQ(queue.pop(), "4");
  EXPECT_EQ(queue.pop(), "5");
  EXPECT_TRUE(queue.empty());
  EXPECT_EQ(queue.bytes(), 0u);
}

TEST(FrameQueue, ABytesBudgetDropsOldFramesButKeepsTheNewOne) {
  FrameQueue queue(100, 10);
  EXPECT_EQ(queue.push("aaaa"), 0u);
  EXPECT_EQ(queue.push("bbbb"), 0u);
  EXPECT_EQ(queue.push("cccc"), 1u);  // 12 bytes > 10: "aaaa" goes
  EXPECT_EQ(queue.bytes(), 8u);
  EXPECT_EQ(queue.push(std::string(50, 'x')), 2u);  // too big on its own, still delivered
  ASSERT_EQ(queue.size(), 1u);
  EXPECT_EQ(queue.pop().size(), 50u);
}

}  // namespace
}  // namespace polarslam::foxglove
