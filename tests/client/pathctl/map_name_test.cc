// pathctl's copy of the map name rule (client/pathctl/map_name.h) against
// the server's (MapStore::ValidateName): the same verdict and the same
// message for every kind of name, so a rule changed on one side fails here.
#include "client/pathctl/map_name.h"

#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "server/map_store.h"

namespace pathd::pathctl {
namespace {

TEST(ValidateMapNameTest, AgreesWithTheServer) {
  const std::vector<std::string> names = {
      "room", "arena2", "a.b_c-D9", std::string(128, 'x'), std::string(129, 'x'),
      std::string(100 * 1024, 'a'), "", ".hidden", "a/b", "with space",
      std::string("nul\0byte", 8), "\xff\xfe", "tab\there", "ok."};
  for (const std::string& name : names) {
    SCOPED_TRACE(name.substr(0, 40));
    const absl::Status client = ValidateMapName(name);
    const absl::Status server = server::MapStore::ValidateName(name);
    EXPECT_EQ(client.code(), server.code());
    EXPECT_EQ(client.message(), server.message());
  }
}

TEST(ValidateMapNameTest, SaysWhatIsWrong) {
  EXPECT_TRUE(ValidateMapName("room").ok());
  EXPECT_EQ(ValidateMapName(std::string(100 * 1024, 'a')).message(),
            "map name is 102400 characters long; the limit is 128");
  EXPECT_EQ(ValidateMapName("").message(), "map name is empty");
}

}  // namespace
}  // namespace pathd::pathctl
