// MQTT topic filters (MQTT 5 4.7) and the reply topic rule of
// ../shared/api-contract.md ("MQTT topics"): a reply goes only to a topic
// without wildcards with a level named reply or replies, not under $,
// spBv1.0/ or canopen/ (except canopen/<gw>/reply/); mqtt.reply-topics
// replaces that default.
#include "mqtt/topic_filter.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace gateway::mqtt {
namespace {

TEST(TopicFilter, SyntaxOfMqtt5_4_7) {
  for (const char* ok : {"a", "a/b", "+", "#", "a/+/c", "a/#", "+/+", "/", "a//b", "$SYS/#", "myapp/reply/+"})
    EXPECT_EQ(topic_filter_problem(ok), "") << ok;
  for (const char* bad : {"", "a/b#", "a/#/c", "#/a", "a+", "a/+b/c", "a/b+"})
    EXPECT_NE(topic_filter_problem(bad), "") << bad;
  EXPECT_NE(topic_filter_problem(std::string("a\0b", 3)), "");
  EXPECT_NE(topic_filter_problem("\xff/reply"), "");
  EXPECT_NE(topic_filter_problem(std::string(65536, 'a')), "");
}

TEST(TopicFilter, MatchingOfMqtt5_4_7) {
  EXPECT_TRUE(topic_matches("a/b", "a/b"));
  EXPECT_FALSE(topic_matches("a/b", "a/b/c"));
  EXPECT_TRUE(topic_matches("a/+/c", "a/x/c"));
  EXPECT_TRUE(topic_matches("a/+/c", "a//c"));  // an empty level is a level
  EXPECT_FALSE(topic_matches("a/+/c", "a/x/y/c"));
  EXPECT_TRUE(topic_matches("a/#", "a"));  // the parent level too (4.7.1.2)
  EXPECT_TRUE(topic_matches("a/#", "a/b/c"));
  EXPECT_FALSE(topic_matches("a/#", "ab"));
  EXPECT_TRUE(topic_matches("#", "anything/at/all"));
  EXPECT_TRUE(topic_matches("+", "a"));
  EXPECT_FALSE(topic_matches("+", "a/b"));
  // Wildcards at the start do not reach topics beginning with $ (4.7.2).
  EXPECT_FALSE(topic_matches("#", "$SYS/x"));
  EXPECT_FALSE(topic_matches("+/reply", "$x/reply"));
  EXPECT_TRUE(topic_matches("$SYS/#", "$SYS/x"));
}

const std::vector<std::string> kNoFilters;

TEST(ReplyTopics, DefaultRuleOfTheContract) {
  auto ok = [](const char* t) { return reply_topic_refusal(t, "gw1", kNoFilters).empty(); };
  EXPECT_TRUE(ok("myapp/reply/42"));
  EXPECT_TRUE(ok("replies/me"));
  EXPECT_TRUE(ok("a/b/replies"));
  EXPECT_TRUE(ok("canopen/gw1/reply/client-7"));  // the gateway's own reply space
  // Its own topics, another gateway's, other systems', the broker's.
  EXPECT_FALSE(ok("canopen/gw1/status"));
  EXPECT_FALSE(ok("canopen/gw1/1/5/state"));
  EXPECT_FALSE(ok("canopen/gw1/1/5/reply"));
  EXPECT_FALSE(ok("canopen/gw2/reply/x"));
  EXPECT_FALSE(ok("canopen/reply"));
  EXPECT_FALSE(ok("spBv1.0/reply/NCMD/x"));
  EXPECT_FALSE(ok("$SYS/reply"));
  EXPECT_FALSE(ok("$share/reply"));
  // No reply level, a level that only contains the word, wildcards.
  EXPECT_FALSE(ok("myapp/answers/42"));
  EXPECT_FALSE(ok("myapp/replyto"));
  EXPECT_FALSE(ok("myapp/reply/+"));
  EXPECT_FALSE(ok("myapp/reply/#"));
  EXPECT_FALSE(ok(""));
  // A loop: its own request topics, even inside its reply space.
  EXPECT_FALSE(ok("canopen/gw1/reply/5/sdo/read"));
  EXPECT_FALSE(ok("canopen/gw1/reply/5/nmt"));
  EXPECT_NE(reply_topic_refusal("canopen/gw1/status", "gw1", kNoFilters).find("canopen/"), std::string_view::npos);
}

TEST(ReplyTopics, ConfiguredFiltersReplaceTheDefault) {
  const std::vector<std::string> filters = {"plant/+/answers", "ops/#"};
  auto ok = [&](const char* t) { return reply_topic_refusal(t, "gw1", filters).empty(); };
  EXPECT_TRUE(ok("plant/7/answers"));
  EXPECT_TRUE(ok("ops"));
  EXPECT_TRUE(ok("ops/a/b"));
  EXPECT_FALSE(ok("myapp/reply/42"));  // the default's examples no longer count
  EXPECT_FALSE(ok("plant/7/8/answers"));
  EXPECT_FALSE(ok("plant/+/answers"));  // a reply topic is a name, never a filter
  // Never the gateway's own request topics, whatever the filters say.
  const std::vector<std::string> all = {"#"};
  EXPECT_FALSE(reply_topic_refusal("canopen/gw1/1/5/sdo/write", "gw1", all).empty());
  EXPECT_TRUE(reply_topic_refusal("canopen/gw1/status", "gw1", all).empty());  // the operator's choice
}

}  // namespace
}  // namespace gateway::mqtt
