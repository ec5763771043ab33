#include "core/io/video_encoder.h"
#include "core/io/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/pixdesc.h>
}

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

namespace gdvr {
namespace {

std::string scratch(const std::string& name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/gdvr_video_" + std::to_string(::getpid()) + "_" + name;
}

bool file_exists(const std::string& path) { return std::ifstream(path).good(); }

// A moving gradient, so inter-frame codecs have real work to do.
Image test_frame(int w, int h, int t) {
  Image img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.set_rgb(x, y, {float((x + t) % w) / w, float(y) / h, 0.5f});
  return img;
}

Image solid(int w, int h, float v) {
  Image img(w, h, 3);
  for (float& p : img.data()) p = v;
  return img;
}

struct InputCloser {
  void operator()(AVFormatContext* f) const { avformat_close_input(&f); }
};
using InputPtr = std::unique_ptr<AVFormatContext, InputCloser>;

struct Probe {
  AVCodecID codec = AV_CODEC_ID_NONE;
  std::string pix_fmt;
  int width = 0, height = 0;
  AVColorPrimaries primaries = AVCOL_PRI_UNSPECIFIED;
  AVColorTransferCharacteristic trc = AVCOL_TRC_UNSPECIFIED;
  AVColorSpace matrix = AVCOL_SPC_UNSPECIFIED;
  AVColorRange range = AVCOL_RANGE_UNSPECIFIED;
  int profile = 0;
  int level = 0;
  AVFieldOrder field_order = AV_FIELD_UNKNOWN;
  int packets = 0;
  std::string format;
};

Probe probe(const std::string& path) {
  Probe p;
  AVFormatContext* raw = nullptr;
  EXPECT_EQ(avformat_open_input(&raw, path.c_str(), nullptr, nullptr), 0) << path;
  if (!raw) return p;
  InputPtr in(raw);
  EXPECT_GE(avformat_find_stream_info(in.get(), nullptr), 0);
  EXPECT_EQ(in->nb_streams, 1u);
  const AVCodecParameters* par = in->streams[0]->codecpar;
  p.codec = par->codec_id;
  p.pix_fmt = par->format >= 0 ? av_get_pix_fmt_name(AVPixelFormat(par->format)) : "none";
  p.width = par->width;
  p.height = par->height;
  p.primaries = par->color_primaries;
  p.trc = par->color_trc;
  p.matrix = par->color_space;
  p.range = par->color_range;
  p.profile = par->profile;
  p.level = par->level;
  p.field_order = par->field_order;
  p.format = in->iformat->name;
  AVPacket* pkt = av_packet_alloc();
  while (av_read_frame(in.get(), pkt) >= 0) {
    ++p.packets;
    av_packet_unref(pkt);
  }
  av_packet_free(&pkt);
  return p;
}

// Decodes the first frame of `path` (to check pixel values end to end).
// `stream_only`: the decoder is given the stream's own parameter sets
// (extradata) and none of the container's fields, so the frame's colour tags
// are those the bitstream carries (H.264's VUI, the ProRes frame header).
struct FrameFree {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
std::unique_ptr<AVFrame, FrameFree> decode_first(const std::string& path, bool stream_only = false) {
  AVFormatContext* raw = nullptr;
  if (avformat_open_input(&raw, path.c_str(), nullptr, nullptr) != 0) return nullptr;
  InputPtr in(raw);
  if (!stream_only) avformat_find_stream_info(in.get(), nullptr);
  const AVCodecParameters* par = in->streams[0]->codecpar;
  const AVCodec* dec = avcodec_find_decoder(par->codec_id);
  if (!dec) return nullptr;
  AVCodecContext* ctx = avcodec_alloc_context3(dec);
  if (!stream_only) {
    avcodec_parameters_to_context(ctx, par);
  } else if (par->extradata_size > 0) {
    ctx->extradata = static_cast<uint8_t*>(av_mallocz(size_t(par->extradata_size) + AV_INPUT_BUFFER_PADDING_SIZE));
    std::copy_n(par->extradata, par->extradata_size, ctx->extradata);
    ctx->extradata_size = par->extradata_size;
  }
  std::unique_ptr<AVFrame, FrameFree> frame(av_frame_alloc());
  bool got = false;
  if (avcodec_open2(ctx, dec, nullptr) == 0) {
    AVPacket* pkt = av_packet_alloc();
    while (!got && av_read_frame(in.get(), pkt) >= 0) {
      avcodec_send_packet(ctx, pkt);
      av_packet_unref(pkt);
      got = avcodec_receive_frame(ctx, frame.get()) == 0;
    }
    if (!got) {
      avcodec_send_packet(ctx, nullptr);
      got = avcodec_receive_frame(ctx, frame.get()) == 0;
    }
    av_packet_free(&pkt);
  }
  avcodec_free_context(&ctx);
  return got ? std::move(frame) : nullptr;
}

struct CodecCase {
  VideoCodec codec;
  const char* ext;
  AVCodecID id;
  const char* pix_fmt;
  AVColorTransferCharacteristic trc;
  AVColorSpace matrix;
  AVColorRange range;
};

class VideoEncoderCodecs : public ::testing::TestWithParam<CodecCase> {};

TEST_P(VideoEncoderCodecs, EncodesTenFramesWithTags) {
  const CodecCase& k = GetParam();
  const std::string path = scratch(std::string("ten.") + k.ext);
  VideoEncoderOptions o;
  o.codec = k.codec;
  o.width = 64;
  o.height = 48;
  o.fps_num = 24;
  Expected<std::unique_ptr<VideoEncoder>> enc = VideoEncoder::open(path, o);
  ASSERT_TRUE(enc.ok()) << enc.status().to_string();
  for (int t = 0; t < 10; ++t) {
    const Status st = (*enc)->add_frame(test_frame(64, 48, t));
    ASSERT_TRUE(st.ok()) << st.to_string();
  }
  EXPECT_FALSE(file_exists(path)) << "visible before close()";
  const Status st = (*enc)->close();
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ((*enc)->frames_written(), 10);
  EXPECT_FALSE(file_exists(temporary_path_for(path)));

  const Probe p = probe(path);
  EXPECT_EQ(p.codec, k.id);
  EXPECT_EQ(p.packets, 10);
  EXPECT_EQ(p.pix_fmt, k.pix_fmt);
  EXPECT_EQ(p.width, 64);
  EXPECT_EQ(p.height, 48);
  EXPECT_EQ(p.primaries, AVCOL_PRI_BT709);
  EXPECT_EQ(p.trc, k.trc);
  EXPECT_EQ(p.matrix, k.matrix);
  EXPECT_EQ(p.range, k.range);
  if (k.codec == VideoCodec::kProRes) {
    EXPECT_EQ(p.profile, FF_PROFILE_PRORES_HQ);
  }
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(
    VideoEncoder, VideoEncoderCodecs,
    ::testing::Values(
        CodecCase{VideoCodec::kH264, "mp4", AV_CODEC_ID_H264, "yuv420p", AVCOL_TRC_BT709,
                  AVCOL_SPC_BT709, AVCOL_RANGE_MPEG},
        CodecCase{VideoCodec::kProRes, "mov", AV_CODEC_ID_PRORES, "yuv422p10le", AVCOL_TRC_BT709,
                  AVCOL_SPC_BT709, AVCOL_RANGE_MPEG},
        CodecCase{VideoCodec::kFfv1, "mkv", AV_CODEC_ID_FFV1, "gbrp10le", AVCOL_TRC_IEC61966_2_1,
                  AVCOL_SPC_RGB, AVCOL_RANGE_JPEG}),
    [](const ::testing::TestParamInfo<CodecCase>& info) {
      return std::string(video_codec_name(info.param.codec));
    });

// The lowest H.264 level (x10) whose frame size and macroblock rate hold
// width x height at `fps` (ITU-T H.264 Table A-1, MaxFS and MaxMBPS): a
// stream tagged below it may be refused by hardware decoders.
int min_h264_level(int width, int height, double fps) {
  struct Level {
    int level;
    long max_fs, max_mbps;
  };
  static const Level kLevels[] = {{30, 1620, 40500},     {31, 3600, 108000},    {32, 5120, 216000},
                                  {40, 8192, 245760},    {42, 8704, 522240},    {50, 22080, 589824},
                                  {51, 36864, 983040},   {52, 36864, 2073600},  {60, 139264, 4177920}};
  const long mbs = long((width + 15) / 16) * ((height + 15) / 16);
  for (const Level& l : kLevels)
    if (mbs <= l.max_fs && double(mbs) * fps <= double(l.max_mbps)) return l.level;
  return 62;
}

// Production sizes (issue: 1080p and 4K shots): the tags, even coded size and
// H.264 level that players and editors rely on, at 1920x1080. 4K is checked
// by hand (docs/service.md, "Output layout"): its encode is too slow here.
TEST(VideoEncoder, FullHdTagsAndLevel) {
  struct Case {
    VideoCodec codec;
    const char* ext;
    const char* pix_fmt;
  };
  for (const Case& k : {Case{VideoCodec::kH264, "mp4", "yuv420p"}, Case{VideoCodec::kProRes, "mov", "yuv422p10le"}}) {
    SCOPED_TRACE(video_codec_name(k.codec));
    const std::string path = scratch(std::string("hd.") + k.ext);
    VideoEncoderOptions o;
    o.codec = k.codec;
    o.width = 1920;
    o.height = 1080;
    o.fps_num = 24;
    auto enc = VideoEncoder::open(path, o);
    ASSERT_TRUE(enc.ok()) << enc.status().to_string();
    EXPECT_EQ((*enc)->encoded_width(), 1920);
    EXPECT_EQ((*enc)->encoded_height(), 1080);
    for (int t = 0; t < 2; ++t) ASSERT_TRUE((*enc)->add_frame(test_frame(1920, 1080, 8 * t)).ok());
    ASSERT_TRUE((*enc)->close().ok());

    const Probe p = probe(path);
    EXPECT_EQ(p.packets, 2);
    EXPECT_EQ(p.pix_fmt, k.pix_fmt);
    EXPECT_EQ(p.width, 1920);
    EXPECT_EQ(p.height, 1080);
    EXPECT_EQ(p.primaries, AVCOL_PRI_BT709);
    EXPECT_EQ(p.trc, AVCOL_TRC_BT709);
    EXPECT_EQ(p.matrix, AVCOL_SPC_BT709);
    EXPECT_EQ(p.range, AVCOL_RANGE_MPEG);
    EXPECT_EQ(p.field_order, AV_FIELD_PROGRESSIVE);
    if (k.codec == VideoCodec::kH264) {
      EXPECT_GE(p.level, min_h264_level(1920, 1080, 24.0));
      EXPECT_LE(p.level, 52);
    } else {
      EXPECT_EQ(p.profile, FF_PROFILE_PRORES_HQ);
    }

    // The bitstream's own tags, which players read where the container has none.
    auto frame = decode_first(path, /* stream_only = */ true);
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->width, 1920);
    EXPECT_EQ(frame->height, 1080);
    EXPECT_EQ(frame->color_primaries, AVCOL_PRI_BT709);
    EXPECT_EQ(frame->color_trc, AVCOL_TRC_BT709);
    EXPECT_EQ(frame->colorspace, AVCOL_SPC_BT709);
    EXPECT_EQ(frame->color_range, AVCOL_RANGE_MPEG);
    std::remove(path.c_str());
  }
}

TEST(VideoEncoder, H264GreyIsLimitedRangeBt709) {
  const std::string path = scratch("grey.mp4");
  VideoEncoderOptions o;
  o.width = 32;
  o.height = 32;
  auto enc = VideoEncoder::open(path, o);
  ASSERT_TRUE(enc.ok()) << enc.status().to_string();
  for (int t = 0; t < 3; ++t) ASSERT_TRUE((*enc)->add_frame(solid(32, 32, 0.5f)).ok());
  ASSERT_TRUE((*enc)->close().ok());
  auto frame = decode_first(path);
  ASSERT_TRUE(frame);
  // Limited range: Y = 16 + 219 * 0.5, chroma neutral at 128.
  EXPECT_NEAR(frame->data[0][16 * frame->linesize[0] + 16], 126, 2);
  EXPECT_NEAR(frame->data[1][8 * frame->linesize[1] + 8], 128, 2);
  std::remove(path.c_str());
}

TEST(VideoEncoder, Ffv1IsLossless10Bit) {
  const std::string path = scratch("lossless.mkv");
  VideoEncoderOptions o;
  o.codec = VideoCodec::kFfv1;
  o.width = 7;  // odd sizes are fine for 4:4:4 RGB
  o.height = 5;
  auto enc = VideoEncoder::open(path, o);
  ASSERT_TRUE(enc.ok()) << enc.status().to_string();
  Image img(7, 5, 3);
  img.set_rgb(2, 3, {0.25f, 0.5f, 1.0f});
  ASSERT_TRUE((*enc)->add_frame(img).ok());
  ASSERT_TRUE((*enc)->close().ok());
  auto frame = decode_first(path);
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->format, AV_PIX_FMT_GBRP10LE);
  auto at = [&](int plane, int x, int y) {
    return reinterpret_cast<const uint16_t*>(frame->data[plane] + y * frame->linesize[plane])[x];
  };
  // GBR plane order: 0 = G, 1 = B, 2 = R.
  EXPECT_NEAR(at(2, 2, 3), 256, 1);
  EXPECT_NEAR(at(0, 2, 3), 512, 1);
  EXPECT_EQ(at(1, 2, 3), 1023);
  EXPECT_EQ(at(0, 0, 0), 0);
  std::remove(path.c_str());
}

TEST(VideoEncoder, OddSizePadsOrRejects) {
  VideoEncoderOptions o;
  o.width = 63;
  o.height = 47;
  const std::string path = scratch("odd.mp4");
  auto enc = VideoEncoder::open(path, o);
  ASSERT_TRUE(enc.ok()) << enc.status().to_string();
  EXPECT_EQ((*enc)->encoded_width(), 64);
  EXPECT_EQ((*enc)->encoded_height(), 48);
  ASSERT_TRUE((*enc)->add_frame(test_frame(63, 47, 0)).ok());
  ASSERT_TRUE((*enc)->close().ok());
  EXPECT_EQ(probe(path).width, 64);
  std::remove(path.c_str());

  o.pad_to_even = false;
  auto rejected = VideoEncoder::open(scratch("odd2.mp4"), o);
  ASSERT_FALSE(rejected.ok());
  EXPECT_EQ(rejected.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(rejected.status().message().find("even"), std::string::npos);
  EXPECT_NE(rejected.status().message().find("h264"), std::string::npos);
}

TEST(VideoEncoder, ErrorsAndAbandonedFiles) {
  VideoEncoderOptions o;
  o.width = 16;
  o.height = 16;
  const std::string path = scratch("abandoned.mp4");
  {
    auto enc = VideoEncoder::open(path, o);
    ASSERT_TRUE(enc.ok());
    ASSERT_TRUE((*enc)->add_frame(solid(16, 16, 0.2f)).ok());
    const Status wrong = (*enc)->add_frame(solid(8, 16, 0.2f));
    EXPECT_EQ(wrong.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(wrong.message().find(path), std::string::npos) << wrong.message();
  }  // destroyed without close(): nothing left behind
  EXPECT_FALSE(file_exists(path));
  EXPECT_FALSE(file_exists(temporary_path_for(path)));

  o.fps_den = 0;
  EXPECT_FALSE(VideoEncoder::open(path, o).ok());
  o.fps_den = 1;
  o.codec = VideoCodec::kProRes;
  auto bad_container = VideoEncoder::open(scratch("prores.mp4"), o);  // ProRes in MP4
  if (!bad_container.ok()) {
    EXPECT_NE(bad_container.status().message().find("prores"), std::string::npos);
  }
  auto bad_dir = VideoEncoder::open("/nonexistent-dir/out.mov", o);
  ASSERT_FALSE(bad_dir.ok());
  EXPECT_NE(bad_dir.status().message().find("/nonexistent-dir/out.mov"), std::string::npos);

  EXPECT_FALSE(parse_video_codec("vp9").ok());
  EXPECT_EQ(parse_video_codec("prores").value(), VideoCodec::kProRes);
}

}  // namespace
}  // namespace gdvr
