// The viewer's static files as pointdagd serves them: app routes to index.html, hashed assets
// cached for good, types, ETags, and nothing outside the files loaded at start.
#include <gtest/gtest.h>

#include <fstream>

#include "service.h"
#include "test_util.h"
#include "web_files.h"

namespace pointdag::server {
namespace {

std::string HeaderOf(const HttpResponse& r, const std::string& name) {
  for (const auto& [n, v] : r.headers) {
    if (n == name) return v;
  }
  return "";
}

class WebFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(scratch_ / "web/assets");
    Write("web/index.html", "<!doctype html><title>pointdag</title>");
    Write("web/assets/app-3F2A9C.js", "console.log('app')");
    Write("web/assets/pdag_decoder-77AB.wasm", std::string("\0asm\1\0\0\0", 8));
    Write("web/secret.txt", "not an asset");
    auto loaded = WebFiles::Load(scratch_ / "web");
    ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
    files_ = std::move(*loaded);
  }
  void Write(const std::string& name, const std::string& text) { std::ofstream(scratch_ / name, std::ios::binary) << text; }
  std::optional<HttpResponse> Get(const std::string& path, std::map<std::string, std::string> headers = {}) const {
    return files_.Serve(HttpRequest{"GET", path, std::move(headers), ""}, path);
  }

  testing::ScratchDir scratch_;
  WebFiles files_;
};

TEST_F(WebFilesTest, AppRoutesServeThePageUncached) {
  for (const char* path : {"/", "/index.html", "/datasets/8739a15344e3f24d", "/datasets/8739a15344e3f24d/3dtiles"}) {
    const auto r = Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 200) << path;
    EXPECT_EQ(r->body, "<!doctype html><title>pointdag</title>") << path;
    EXPECT_EQ(HeaderOf(*r, "Content-Type"), "text/html; charset=utf-8");
    EXPECT_EQ(HeaderOf(*r, "Cache-Control"), "no-cache");
    EXPECT_NE(HeaderOf(*r, "Content-Security-Policy").find("default-src 'self'"), std::string::npos);
  }
}

TEST_F(WebFilesTest, AssetsAreImmutableWithTheirTypes) {
  const auto js = Get("/assets/app-3F2A9C.js");
  ASSERT_TRUE(js);
  EXPECT_EQ(js->status, 200);
  EXPECT_EQ(js->body, "console.log('app')");
  EXPECT_EQ(HeaderOf(*js, "Content-Type"), "text/javascript; charset=utf-8");
  EXPECT_EQ(HeaderOf(*js, "Cache-Control"), "public, max-age=31536000, immutable");
  EXPECT_EQ(HeaderOf(*js, "X-Content-Type-Options"), "nosniff");
  const auto wasm = Get("/assets/pdag_decoder-77AB.wasm");
  ASSERT_TRUE(wasm);
  EXPECT_EQ(HeaderOf(*wasm, "Content-Type"), "application/wasm");
  EXPECT_EQ(wasm->body.size(), 8u);
}

TEST_F(WebFilesTest, ConditionalRequestsGet304) {
  const auto first = Get("/assets/app-3F2A9C.js");
  ASSERT_TRUE(first);
  const std::string etag = HeaderOf(*first, "ETag");
  ASSERT_EQ(etag.size(), 18u);  // "16 hex digits"
  const auto again = Get("/assets/app-3F2A9C.js", {{"if-none-match", etag}});
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 304);
  EXPECT_TRUE(again->body.empty());
  const auto page = Get("/", {{"if-none-match", "\"0000000000000000\""}});
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
}

TEST_F(WebFilesTest, NothingOutsideTheLoadedFiles) {
  for (const char* path : {"/secret.txt", "/assets/../secret.txt", "/assets/", "/assets/missing.js", "/datasets/",
                           "/datasets/not-an-id", "/datasets/8739a153/tiles", "/v1/datasets", "/web/index.html"}) {
    EXPECT_FALSE(Get(path)) << path;
  }
}

TEST_F(WebFilesTest, AMissingFolderIsAnErrorAndEmptyMeansOff) {
  const auto missing = WebFiles::Load(scratch_ / "nowhere");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("nowhere/index.html"), std::string::npos);
  const auto off = WebFiles::Load("");
  ASSERT_TRUE(off.ok());
  EXPECT_FALSE(off->enabled());
  EXPECT_FALSE(off->Serve(HttpRequest{"GET", "/", {}, ""}, "/"));
}

TEST(ContentType, ByExtension) {
  EXPECT_EQ(ContentTypeFor("a.css"), "text/css; charset=utf-8");
  EXPECT_EQ(ContentTypeFor("a.js.map"), "application/json");
  EXPECT_EQ(ContentTypeFor("README"), "application/octet-stream");
}

}  // namespace
}  // namespace pointdag::server
