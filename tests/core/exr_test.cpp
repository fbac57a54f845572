#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <vector>

#include "shimmer/core/exr_input.h"
#include "shimmer/core/exr_output.h"
#include "temp_dir.h"

namespace shimmer {
namespace {

// The one writer and the one reader: float planes round-trip bit for bit,
// half planes to half precision, compressed or not.
TEST(Exr, PlanesRoundTripThroughTheWriterAndTheReader) {
  testing::TempDir dir;
  const int w = 37, h = 23;  // not a multiple of the 16-line ZIP block
  std::vector<float> a(w * h), b(w * h);
  for (int i = 0; i < w * h; ++i) a[i] = std::sin(0.1f * i) * 1e3f, b[i] = 0.25f * (i % 7);
  for (ExrCompression c : {ExrCompression::kNone, ExrCompression::kZip}) {
    const auto file = dir / (c == ExrCompression::kZip ? "zip.exr" : "none.exr");
    ASSERT_TRUE(WriteExr(file, w, h, {{"specular.R", a.data()}, {"Y", b.data(), true}}, c));
    auto in = ExrInput::Open(file, true);
    ASSERT_TRUE(in) << in.error();
    ASSERT_EQ(in->parts().size(), 1u);
    EXPECT_EQ(in->parts()[0].width, w);
    EXPECT_EQ(in->parts()[0].height, h);
    std::vector<float> ra(w * h), rb(w * h);
    ASSERT_TRUE(in->Read(0, {{"specular.R", ra.data()}, {"Y", rb.data()}}));
    EXPECT_EQ(ra, a);
    EXPECT_EQ(rb, b);  // multiples of 0.25 are exact in half
  }
  EXPECT_EQ(dir.Names(), (std::vector<std::string>{"none.exr", "zip.exr"}));
}

TEST(Exr, BadFilesAreNamed) {
  testing::TempDir dir;
  std::ofstream(dir / "junk.exr") << "not an exr";
  auto junk = ExrInput::Open(dir / "junk.exr");
  ASSERT_FALSE(junk);
  EXPECT_NE(junk.error().find("junk.exr: not a readable EXR file"), std::string::npos) << junk.error();
  EXPECT_EQ(ExrInput::Open(dir / "none.exr").error(), (dir / "none.exr").string() + ": no such file");
  std::vector<float> p(4);
  auto unwritable = WriteExr(dir / "no-dir" / "f.exr", 2, 2, {{"Y", p.data()}});
  ASSERT_FALSE(unwritable);
  EXPECT_EQ(unwritable.code(), ErrorCode::kIo);
  EXPECT_NE(unwritable.error().find("f.exr"), std::string::npos);
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"junk.exr"});
}

}  // namespace
}  // namespace shimmer
