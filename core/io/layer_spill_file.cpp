#include "core/io/layer_spill_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <filesystem>
#include <cstdint>
#include <cstring>

#include "core/io/atomic_file.h"

namespace gdvr {

namespace {

constexpr char kMagic[8] = {'G', 'D', 'V', 'R', 'S', 'P', 'L', '1'};
// Far above any real layer or channel count: a corrupt header is refused
// before it asks for absurd allocations.
constexpr uint32_t kMaxNames = 1u << 16;
constexpr uint32_t kMaxNameBytes = 1u << 12;

void put_u32(std::string* out, uint32_t v) { out->append(reinterpret_cast<const char*>(&v), sizeof v); }
void put_name(std::string* out, const std::string& s) {
  put_u32(out, uint32_t(s.size()));
  out->append(s);
}

Status write_all(int fd, const char* data, size_t bytes, const std::string& path) {
  while (bytes > 0) {
    const ssize_t n = ::write(fd, data, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return internal_error(path + ": cannot write spill file: " + std::strerror(errno));
    data += n;
    bytes -= size_t(n);
  }
  return Status::Ok();
}

Status read_all(int fd, char* data, size_t bytes, long long offset, const std::string& path) {
  while (bytes > 0) {
    const ssize_t n = ::pread(fd, data, bytes, off_t(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      return internal_error(path + ": spill file ends early or cannot be read" + (n < 0 ? std::string(": ") + std::strerror(errno) : ""));
    data += n;
    bytes -= size_t(n);
    offset += n;
  }
  return Status::Ok();
}

}  // namespace

Status write_layer_spill(const std::string& path, const LayeredImage& image) {
  if (image.layers.empty()) return invalid_argument(path + ": no layers to spill");
  const int w = image.layers.front().image.width(), h = image.layers.front().image.height();
  std::string header(kMagic, sizeof kMagic);
  put_u32(&header, uint32_t(w));
  put_u32(&header, uint32_t(h));
  put_u32(&header, uint32_t(image.layers.size()));
  for (const ImageLayer& l : image.layers) {
    if (l.image.width() != w || l.image.height() != h || size_t(l.image.channels()) != l.channels.size())
      return invalid_argument(path + ": layer '" + l.name + "' is " + std::to_string(l.image.width()) + "x" +
                              std::to_string(l.image.height()) + " with " + std::to_string(l.image.channels()) +
                              " channels, the frame is " + std::to_string(w) + "x" + std::to_string(h));
    put_name(&header, l.name);
    put_u32(&header, uint32_t(l.channels.size()));
    for (const std::string& c : l.channels) put_name(&header, c);
  }
  // Written under a temporary name and renamed: a spill file is either whole or absent.
  const std::string tmp = temporary_path_for(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return internal_error(path + ": cannot create spill file: " + std::strerror(errno));
  Status st = write_all(fd, header.data(), header.size(), path);
  for (const ImageLayer& l : image.layers) {
    if (!st.ok()) break;
    st = write_all(fd, reinterpret_cast<const char*>(l.image.data().data()), l.image.data().size() * sizeof(float), path);
  }
  ::close(fd);
  if (!st.ok()) {
    discard_temporary(tmp);
    return st;
  }
  return commit_temporary(tmp, path);
}

long long layer_pixel_bytes(const LayeredImage& image) {
  long long n = 0;
  for (const ImageLayer& layer : image.layers) n += (long long)layer.image.data().size() * (long long)sizeof(float);
  return n;
}

Expected<std::unique_ptr<LayerSpillFile>> LayerSpillFile::spill(const std::string& dir, const LayeredImage& image) {
  // A name unique in the process (and, with the pid, among processes sharing the folder).
  static std::atomic<long long> counter{0};
  const std::string path = (std::filesystem::path(dir.empty() ? std::filesystem::temp_directory_path().string() : dir) /
                            ("gdvr_spill_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".raw"))
                               .string();
  GDVR_RETURN_IF_ERROR(write_layer_spill(path, image));
  auto file = open(path);
  std::error_code ec;
  std::filesystem::remove(path, ec);  // the open descriptor keeps the pixels
  return file;
}

Expected<std::unique_ptr<LayerSpillFile>> LayerSpillFile::open(const std::string& path) {
  std::unique_ptr<LayerSpillFile> f(new LayerSpillFile());
  f->path_ = path;
  f->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->fd_ < 0) return not_found(path + ": cannot open spill file: " + std::strerror(errno));
  long long at = 0;
  auto u32 = [&](uint32_t* v) -> Status {
    GDVR_RETURN_IF_ERROR(read_all(f->fd_, reinterpret_cast<char*>(v), sizeof *v, at, path));
    at += sizeof *v;
    return Status::Ok();
  };
  auto name = [&](std::string* s) -> Status {
    uint32_t n = 0;
    GDVR_RETURN_IF_ERROR(u32(&n));
    if (n > kMaxNameBytes) return invalid_argument(path + ": corrupt spill file (name of " + std::to_string(n) + " bytes)");
    s->resize(n);
    GDVR_RETURN_IF_ERROR(read_all(f->fd_, s->data(), n, at, path));
    at += n;
    return Status::Ok();
  };
  char magic[sizeof kMagic];
  GDVR_RETURN_IF_ERROR(read_all(f->fd_, magic, sizeof magic, 0, path));
  if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) return invalid_argument(path + ": not a gdvr spill file");
  at = sizeof kMagic;
  uint32_t w = 0, h = 0, layers = 0;
  GDVR_RETURN_IF_ERROR(u32(&w));
  GDVR_RETURN_IF_ERROR(u32(&h));
  GDVR_RETURN_IF_ERROR(u32(&layers));
  if (w == 0 || h == 0 || w > (1u << 20) || h > (1u << 20) || layers > kMaxNames)
    return invalid_argument(path + ": corrupt spill file header");
  f->width_ = int(w);
  f->height_ = int(h);
  for (uint32_t i = 0; i < layers; ++i) {
    Layer l;
    GDVR_RETURN_IF_ERROR(name(&l.name));
    uint32_t channels = 0;
    GDVR_RETURN_IF_ERROR(u32(&channels));
    if (channels == 0 || channels > kMaxNames) return invalid_argument(path + ": corrupt spill file (layer '" + l.name + "')");
    l.channels.resize(channels);
    for (std::string& c : l.channels) GDVR_RETURN_IF_ERROR(name(&c));
    f->layers_.push_back(std::move(l));
  }
  for (Layer& l : f->layers_) {
    l.offset = at;
    at += (long long)w * h * (long long)l.channels.size() * (long long)sizeof(float);
  }
  return f;
}

LayerSpillFile::~LayerSpillFile() {
  if (fd_ >= 0) ::close(fd_);
}

Expected<LayeredImage> LayerSpillFile::read(const PixelRect& rect) const {
  if (rect.empty() || !PixelRect::whole(width_, height_).contains(rect))
    return invalid_argument(path_ + ": region " + rect.to_string() + " is not inside the " + std::to_string(width_) +
                            "x" + std::to_string(height_) + " frame");
  LayeredImage out;
  for (const Layer& l : layers_) {
    const int C = int(l.channels.size());
    Image img(rect.width(), rect.height(), C);
    const size_t row_bytes = size_t(rect.width()) * C * sizeof(float);
    for (int y = rect.y0; y < rect.y1; ++y) {
      const long long offset = l.offset + ((long long)y * width_ + rect.x0) * C * (long long)sizeof(float);
      char* to = reinterpret_cast<char*>(img.data().data() + size_t(y - rect.y0) * rect.width() * C);
      GDVR_RETURN_IF_ERROR(read_all(fd_, to, row_bytes, offset, path_));
    }
    out.add(l.name, l.channels, std::move(img));
  }
  return out;
}

}  // namespace gdvr
