// Procedural grey textures and their filtered sampling.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace synth {

// Where one image sample lands in a texture and how far it reaches: texel coordinates at the
// full-resolution level and their derivatives along the image x and y axes (per sample, not per
// pixel, so supersampling narrows the footprint).
struct Footprint {
	double u, v;
	double dudx, dvdx, dudy, dvdy;
};

// A square, power-of-two, seamlessly tiling 8-bit texture with its mip pyramid. Sampling wraps
// around, so texel coordinates may be any size (world metres on the ground become large).
class Texture {
public:
	explicit Texture(const cv::Mat &base); // CV_8UC1, square, power-of-two side

	// Filtered grey value in [0, 255]: anisotropic trilinear, i.e. a few trilinear taps spread
	// along the long axis of the footprint, so grazing surfaces stay sharp across and do not
	// alias along.
	float sample(const Footprint &fp) const;

private:
	// One mip level, stored in 8x8 blocks of texels (one cache line each) rather than rows, so
	// that a bilinear lookup and its neighbours along any direction mostly share cache lines.
	struct Level {
		std::vector<uint8_t> texels;
		int mask;        // side - 1 (sides are powers of two)
		int block_shift; // log2 of the block side: 3, or less for the smallest levels
		int row_shift;   // log2 of the blocks per row of blocks
		float scale;     // from texel coordinates of level 0 to this level's

		uint8_t at(int x, int y) const
		{
			const int b = (1 << block_shift) - 1;
			return texels[size_t(((((y >> block_shift) << row_shift) + (x >> block_shift)) << (2 * block_shift)) |
					     ((y & b) << block_shift) | (x & b))];
		}
	};

	float bilinear(const Level &level, float u, float v) const;
	float trilinear(float u, float v, float lod) const;

	std::vector<Level> levels_;
};

// A tileable "dead leaves" texture: opaque shapes of random grey drawn in scale bands from large
// to small, over multi-octave value noise, with fine grain on top. Dead leaves give the
// scale-invariant statistics of natural images, so there are corners at every scale and nothing
// periodic for a matcher to confuse. Deterministic in (size, seed).
cv::Mat generate_texture(int size, uint64_t seed);

} // namespace synth
