// A scene from Mitsuba XML text, with the FrameScene built on it, for tests
// that trace single rays into small hand-written scenes.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "core/render/frame_scene.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr::test {

struct XmlScene {
  Scene desc;
  std::unique_ptr<FrameScene> scene;  // null (with a test failure) if the XML did not load
};

inline XmlScene load_xml_scene(const std::string& xml) {
  XmlScene l;
  auto s = load_mitsuba_scene_from_string(xml, ".", {});
  EXPECT_TRUE(s.ok()) << s.status().to_string();
  if (!s.ok()) return l;
  l.desc = std::move(s.value());
  auto fs = FrameScene::create(l.desc, {});
  EXPECT_TRUE(fs.ok()) << fs.status().to_string();
  if (fs.ok()) l.scene = std::move(fs.value());
  return l;
}

}  // namespace gdvr::test
