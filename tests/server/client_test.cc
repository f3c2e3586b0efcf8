// The client against a hostile server (issue 11): a small HTTP server on loopback plays the
// attacker, answering crafted bodies. FetchDataset must return an error, never hang, abort or
// allocate by what it is told.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <map>
#include <thread>

#include "../codec/hostile_pdag.h"
#include "../codec/test_util.h"
#include "client.h"

namespace pointdag {
namespace {

// Answers each request with handler(target): a complete raw HTTP response. Keep-alive, one
// connection at a time, as the client uses it.
class HostileServer {
 public:
  using Handler = std::function<std::string(const std::string& target)>;
  explicit HostileServer(Handler handler) : handler_(std::move(handler)) {
    listener_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof(addr);
    EXPECT_EQ(bind(listener_, reinterpret_cast<sockaddr*>(&addr), len), 0);
    EXPECT_EQ(listen(listener_, 4), 0);
    getsockname(listener_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { Serve(); });
  }
  ~HostileServer() {
    shutdown(listener_, SHUT_RDWR);
    close(listener_);
    thread_.join();
  }
  std::string Url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/v1/datasets/1"; }
  int requests() const { return requests_; }

 private:
  void Serve() {
    for (;;) {
      const int fd = accept(listener_, nullptr, nullptr);
      if (fd < 0) return;
      std::string in;
      char buf[4096];
      for (;;) {
        const size_t end = in.find("\r\n\r\n");
        if (end == std::string::npos) {
          const ssize_t n = read(fd, buf, sizeof(buf));
          if (n <= 0) break;
          in.append(buf, static_cast<size_t>(n));
          continue;
        }
        const size_t sp1 = in.find(' '), sp2 = in.find(' ', sp1 + 1);
        const std::string target = in.substr(sp1 + 1, sp2 - sp1 - 1);
        in.erase(0, end + 4);
        ++requests_;
        const std::string answer = handler_(target);
        // A broken pipe is how an over-long body ends when the client stops reading: not an error here.
        if (send(fd, answer.data(), answer.size(), MSG_NOSIGNAL) < 0) break;
      }
      close(fd);
    }
  }

  Handler handler_;
  int listener_ = -1;
  uint16_t port_ = 0;
  std::atomic<int> requests_{0};
  std::thread thread_;
};

std::string Answer(const std::string& body, const std::string& extra_headers = "") {
  return "HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(body.size()) + "\r\n" + extra_headers + "\r\n" + body;
}

const std::string kDataset =
    R"({"levels": 2, "tile_depth": 4, "bounds": {"min": [0, 0, 0], "max": [32, 32, 32]}, "voxel_size": 1.0, "source": {"points": 9}})";
const std::string kRootPage =
    R"({"tiles": [{"level": 0, "x": 0, "y": 0, "z": 0}, {"level": 1, "x": 1, "y": 0, "z": 0}], "pages": []})";

// A dataset whose answers are `dataset`, `page` for every hierarchy page and `tile` for every tile.
HostileServer::Handler Serving(std::string dataset, std::string page, std::string tile = "") {
  return [=](const std::string& target) {
    if (target.find("/hierarchy/") != std::string::npos) return Answer(page);
    if (target.find("/tiles/") != std::string::npos) return Answer(tile);
    return Answer(dataset);
  };
}

std::string PdagTile(int depth) {
  PdagFile file;
  file.meta = testing::MinimalMeta(uint64_t{1} << (3 * depth), depth);
  file.geometry = EncodeDag(testing::DenseCube(depth), GeometryCoder::kContext).value();
  const auto bytes = SerializePdag(file);
  return {bytes.begin(), bytes.end()};
}

Status Fetch(const HostileServer& server, client::FetchLimits limits = {}) {
  return client::FetchDataset(server.Url(), std::nullopt, {}, limits).status();
}

TEST(HostileServer, AnHonestAnswerFetchesItsTile) {  // the attacker's server is sound when it tells the truth
  HostileServer server(Serving(kDataset, kRootPage, PdagTile(4)));
  auto fetched = client::FetchDataset(server.Url(), std::nullopt);
  ASSERT_TRUE(fetched.ok()) << fetched.status().ToString();
  EXPECT_EQ(fetched->tiles, 1u);
  EXPECT_EQ(fetched->grid.morton.size(), 4096u);
  EXPECT_EQ(fetched->grid.depth, 5);
}

TEST(HostileServer, RepeatedHierarchyPageIsAnErrorNotALoop) {
  // Every page lists page (4, 0, 0, 0) again: the walk used to follow it forever.
  const std::string deep = R"({"levels": 10, "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1.0})";
  HostileServer cycle(Serving(deep, R"({"tiles": [], "pages": [{"level": 4, "x": 0, "y": 0, "z": 0}]})"));
  Status status = Fetch(cycle);
  EXPECT_EQ(status.code(), StatusCode::kMalformed) << status.ToString();
  EXPECT_NE(status.message().find("not below it"), std::string::npos) << status.ToString();
  EXPECT_LE(cycle.requests(), 3);
  // The same page listed twice is fetched once, then refused.
  const std::string dataset = R"({"levels": 6, "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1.0})";
  HostileServer twice(Serving(dataset, R"({"tiles": [], "pages": [{"level": 4, "x": 1, "y": 0, "z": 0}, {"level": 4, "x": 1, "y": 0, "z": 0}]})"));
  status = Fetch(twice);
  EXPECT_EQ(status.code(), StatusCode::kMalformed) << status.ToString();
  EXPECT_NE(status.message().find("page 4/1/0/0 twice"), std::string::npos) << status.ToString();
}

TEST(HostileServer, MissingKeysAndWrongTypesAreErrors) {
  const std::pair<std::string, std::string> cases[] = {
      {R"({"tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1})", "'levels' is missing"},
      {R"({"levels": "2", "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1})", "'levels' is not an integer"},
      {R"({"levels": 2, "tile_depth": 4, "voxel_size": 1})", "'bounds/min' is missing"},
      {R"({"levels": 2, "tile_depth": 4, "bounds": [], "voxel_size": 1})", "'bounds/' is not an object"},
      {R"({"levels": 2, "tile_depth": 64, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1})", "'tile_depth' is outside 2..8"},
      {R"({"levels": 30, "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1})", "'levels' is outside 1..18"},
      {R"({"levels": 2, "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": -1})", "'voxel_size' is not positive"},
      {R"([1, 2])", "is not a JSON object"},
      {std::string(100000, '['), "nested deeper"},
  };
  for (const auto& [dataset, reason] : cases) {
    HostileServer server(Serving(dataset, kRootPage));
    const Status status = Fetch(server);
    EXPECT_EQ(status.code(), StatusCode::kMalformed) << dataset.substr(0, 80);
    EXPECT_NE(status.message().find(reason), std::string::npos) << status.ToString();
  }
  const std::pair<std::string, std::string> pages[] = {
      {R"({"pages": []})", "'tiles' is missing"},
      {R"({"tiles": [{"level": 1, "x": 0, "y": 0}]})", "'z' is missing"},
      {R"({"tiles": [{"level": 1, "x": 2, "y": 0, "z": 0}]})", "'x' is outside 0..1"},
      {R"({"tiles": [{"level": 1.5, "x": 0, "y": 0, "z": 0}]})", "'level' is not an integer"},
      {R"({"tiles": [{"level": 9, "x": 0, "y": 0, "z": 0}]})", "'level' is outside 0..1"},
      {R"({"tiles": {}})", "'tiles' is not an array"},
  };
  for (const auto& [page, reason] : pages) {
    HostileServer server(Serving(kDataset, page));
    const Status status = Fetch(server);
    EXPECT_EQ(status.code(), StatusCode::kMalformed) << page;
    EXPECT_NE(status.message().find(reason), std::string::npos) << status.ToString();
  }
}

TEST(HostileServer, HugeContentLengthIsRefusedWhileReading) {
  // Declares 64 GiB and sends a few bytes, then waits: the client must not wait for, or reserve, them.
  HostileServer server([](const std::string&) { return std::string("HTTP/1.1 200 OK\r\nContent-Length: 68719476736\r\n\r\n{\"lev"); });
  const Status status = Fetch(server);
  EXPECT_EQ(status.code(), StatusCode::kResourceLimit) << status.ToString();
  // The bound is the caller's: a body over it is refused, under it accepted.
  HostileServer honest(Serving(kDataset, kRootPage, PdagTile(4)));
  client::FetchLimits tight;
  tight.max_body_bytes = 100;
  EXPECT_EQ(Fetch(honest, tight).code(), StatusCode::kResourceLimit);
}

TEST(HostileServer, TilesThatAreNotWhatTheyShouldBeAreErrors) {
  const std::pair<std::string, std::string> cases[] = {
      {"<html><body>Not a tile, but an error page of some proxy</body></html>", "not a .pdag file"},
      {PdagTile(10), "this decoder allows"},  // a billion voxels where a tile holds 4096 at most
      {PdagTile(3), "is not 4 levels deep"},
  };
  for (const auto& [tile, reason] : cases) {
    HostileServer server(Serving(kDataset, kRootPage, tile));
    const Status status = Fetch(server);
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find(reason), std::string::npos) << status.ToString();
    EXPECT_NE(status.message().find("tiles/1/1/0/0"), std::string::npos) << status.ToString();
  }
}

// Shadow layers (PROTOCOL §3.2) from the attacker: each is checked against its tile's own voxel
// count before anything is allocated; an honest one lands voxel for voxel in `light`.
TEST(HostileServer, ShadowLayersThatLieAreErrors) {
  const std::string shaded = kDataset.substr(0, kDataset.size() - 1) + R"(, "shadows": {"kind": "direction", "samples": 1}})";
  const auto layer_of = [](uint32_t n, uint8_t value) {
    const auto bytes = EncodeShadowLayer({ShadowKind::kDirection, 1, std::vector<uint8_t>(n, value)}).value();
    return std::string(bytes.begin(), bytes.end());
  };
  const auto serving = [&](const std::string& dataset, const std::string& layer) {
    return [=](const std::string& target) {
      if (target.find("/shadows/tiles/") != std::string::npos) return Answer(layer);
      return Serving(dataset, kRootPage, PdagTile(4))(target);
    };
  };
  {
    HostileServer honest(serving(shaded, layer_of(4096, 255)));
    const auto fetched = client::FetchDataset(honest.Url(), std::nullopt, {}, {}, true);
    ASSERT_TRUE(fetched.ok()) << fetched.status().ToString();
    EXPECT_EQ(fetched->light, std::vector<uint8_t>(4096, 255));
  }
  std::string huge = layer_of(4096, 0);
  huge[8] = huge[9] = huge[10] = huge[11] = '\xFF';  // 2^32 - 1 voxels claimed for a tile of 4096
  const std::pair<std::string, std::string> cases[] = {
      {layer_of(4095, 255), "covers 4095 voxels; its tile has 4096"},
      {huge, "covers 4294967295 voxels; its tile has 4096"},
      {"<html><body>Not a layer</body></html>", "not a shadow layer"},
  };
  for (const auto& [layer, reason] : cases) {
    HostileServer server(serving(shaded, layer));
    const Status status = client::FetchDataset(server.Url(), std::nullopt, {}, {}, true).status();
    EXPECT_EQ(status.code(), StatusCode::kMalformed) << status.ToString();
    EXPECT_NE(status.message().find(reason), std::string::npos) << status.ToString();
    EXPECT_NE(status.message().find("shadows/tiles/1/1/0/0"), std::string::npos) << status.ToString();
  }
  HostileServer unshaded(serving(kDataset, layer_of(4096, 255)));
  EXPECT_EQ(client::FetchDataset(unshaded.Url(), std::nullopt, {}, {}, true).status().code(), StatusCode::kInvalidArgument);
}

TEST(HostileServer, TooManyPagesOrTilesAreResourceLimits) {
  const std::string dataset = R"({"levels": 10, "tile_depth": 4, "bounds": {"min": [0, 0, 0]}, "voxel_size": 1.0})";
  std::string page = R"({"tiles": [], "pages": [)";
  for (int x = 0; x < 16; ++x) page += std::string(x ? "," : "") + R"({"level": 4, "x": )" + std::to_string(x) + R"(, "y": 0, "z": 0})";
  page += "]}";
  HostileServer server(Serving(dataset, page));
  client::FetchLimits limits;
  limits.max_pages = 8;
  EXPECT_EQ(Fetch(server, limits).code(), StatusCode::kResourceLimit);
}

}  // namespace
}  // namespace pointdag
