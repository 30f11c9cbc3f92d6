#pragma once
// Pass roles and the frame (a set of named passes) that every filter reads.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "image/deep.h"
#include "image/lightfield.h"
#include "image/image.h"

namespace mcr {

enum class Role {
  Colour,          // noisy radiance, RGB
  Albedo,          // RGB
  Normal,          // XYZ
  Position,        // XYZ
  Depth,           // 1 channel
  Motion,          // XY (+ZW): Blender Vector, pixels, previous minus current, y up
  Variance,        // 1 or 3 channels: per-pixel variance of the colour estimate
  SecondPosition,  // XYZ at the second hit (Guo & Pan)
  SecondNormal,    // XYZ at the second hit
  SampleCount,     // 1 channel; 0 marks a hole in sparse renders
  Alpha,           // 1 channel
  // Blender's light passes (components=light_passes, pipeline/components.h): the
  // direct/indirect passes hold light already divided by their colour pass, RGB each.
  DiffuseDirect, DiffuseIndirect, DiffuseColour,
  GlossyDirect, GlossyIndirect, GlossyColour,
  TransmissionDirect, TransmissionIndirect, TransmissionColour,
  Emission, Environment,
};

inline constexpr Role kAllRoles[] = {Role::Colour,   Role::Albedo,         Role::Normal,
                                     Role::Position, Role::Depth,          Role::Motion,
                                     Role::Variance, Role::SecondPosition, Role::SecondNormal,
                                     Role::SampleCount, Role::Alpha,
                                     Role::DiffuseDirect, Role::DiffuseIndirect, Role::DiffuseColour,
                                     Role::GlossyDirect, Role::GlossyIndirect, Role::GlossyColour,
                                     Role::TransmissionDirect, Role::TransmissionIndirect, Role::TransmissionColour,
                                     Role::Emission, Role::Environment};

const char* role_name(Role r);                           // "colour", "albedo", ...
std::optional<Role> role_from_name(const std::string&);  // accepts "color", "diffuse_color" too
int role_channels(Role r);                               // channels a filter may rely on

// Coordinate space of a geometric pass; filters that compare geometry across
// frames need World, edge-stopping filters are happy with either.
enum class Space { None, World, Camera };
const char* space_name(Space s);

struct Pass {
  Role role = Role::Colour;
  std::string name;                   // channel group, e.g. "ViewLayer.Denoising Normal"
  std::string source;                 // file it came from
  std::vector<std::string> channels;  // full channel names in that file, in order
  Space space = Space::None;
  int priority = 0;                   // higher wins when a role has several candidates
  Image image;
};

// The pass with other pixels (a crop, an enlargement): every other field kept, the old pixels
// never copied.
Pass with_pixels(const Pass& p, Image image);

// Which candidate of a role a filter prefers. Blender writes both a filtered
// camera-space "Denoising Normal" and a world-space "Normal".
enum class Prefer { Feature, Geometry };

// Where the pixels sit: the OpenEXR data window's origin and the display window
// (full_width 0 = the data window itself). Kept so that crops and overscan
// survive a read-filter-write round trip.
struct PixelWindow {
  int x = 0, y = 0;
  int full_x = 0, full_y = 0, full_width = 0, full_height = 0;
};

// One frame: colour plus feature passes, all the same size. A deep frame also
// carries its per-sample buffer; `colour` then holds the flattened image.
class Frame {
 public:
  int width = 0, height = 0;
  std::string path;   // input file, for messages
  std::string layer;  // chosen view layer ("" for plain files)
  std::vector<std::string> layers;  // every layer in the file
  int frame_number = 0;
  PixelWindow window;
  std::vector<Pass> passes;
  std::vector<Pass> extra;  // channels with no role, carried by --keep-passes
  std::shared_ptr<const DeepSamples> deep;
  // A light-field deep file, decoded once when read (image/lightfield.h): the flat colour and
  // every light-field filter use this one.
  std::shared_ptr<const LightField> lightfield;

  bool has(Role r) const { return find(r) != nullptr; }
  const Pass* find(Role r, Prefer p = Prefer::Feature) const;
  // Throws Errc::MissingPass naming the role and the file.
  const Pass& get(Role r, Prefer p = Prefer::Feature) const;
  const Image& image(Role r, Prefer p = Prefer::Feature) const { return get(r, p).image; }

  // A frame of width x height that names the same file, layer and frame number, with no passes,
  // samples or window (a crop, an enlargement or a split of this one fills them).
  Frame header(int w, int h) const;

  // Adds or replaces the pass of that role (same name replaces, else appended).
  void put(Pass p);
  // Checks every pass has the frame's size; throws Errc::SizeMismatch.
  void check_sizes() const;
};

}  // namespace mcr
