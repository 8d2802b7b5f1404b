// problem+json (RFC 9457) of a core::Problem: REST, MQTT and the HTTP
// server's own errors answer with it.
#include "messages/problem_json.hpp"

#include <gtest/gtest.h>

#include "canopen/sdo/abort.hpp"

namespace gateway {
namespace {

using core::Problem;
using core::sdo_problem;

TEST(ProblemJson, Rfc9457FieldsInOrderWithDefaults) {
  Problem p;
  p.status = 400;
  p.detail = "bad \"index\" <1017>";
  EXPECT_EQ(problem_json(p),
            R"({"type":"about:blank","title":"Bad Request","status":400,"detail":"bad \"index\" <1017>"})");
  p = sdo_problem(make_error_code(canopen::SdoAbort::NoSuchObject), true);
  p.type = "https://example.com/sdo";
  EXPECT_EQ(problem_json(p, "c-1"),
            std::string(R"({"type":"https://example.com/sdo","title":"SDO abort","status":422,"detail":")") +
                std::string(canopen::sdo_abort_text(0x06020000)) + R"(","abortCode":"0x06020000","correlationId":"c-1"})");
  // Not UTF-8: read as Latin-1, so the document stays valid JSON.
  Problem latin1;
  latin1.status = 404;
  latin1.detail = "caf\xe9";
  EXPECT_EQ(problem_json(latin1), R"({"type":"about:blank","title":"Not Found","status":404,"detail":"café"})");
}

}  // namespace
}  // namespace gateway
