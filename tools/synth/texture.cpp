#include "texture.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace synth {

namespace {

// Beyond this many taps the footprint is widened instead: an 8:1 ellipse is already the ground
// about 13 m ahead of a camera 1.6 m up, and further away a little blur is what a lens does too.
constexpr int kMaxTaps = 8;

// Fixed-point bits for OpenCV's drawing functions, so shapes land at sub-texel positions.
constexpr int kShift = 4;
constexpr double kOne = 1 << kShift;

cv::Point fixed(cv::Point2d p)
{
	return {cvRound(p.x * kOne), cvRound(p.y * kOne)};
}

// Smooth random field in [-1, 1] with `grid` cells across, tiling with period `size`: cubic
// interpolation of a random lattice padded by wrapping, so both edges see the same neighbours.
cv::Mat value_noise(int size, int grid, cv::RNG &rng)
{
	cv::Mat cells(grid, grid, CV_32F);
	rng.fill(cells, cv::RNG::UNIFORM, -1.0, 1.0);
	const int pad = 2, scale = size / grid;
	cv::Mat padded, big;
	cv::copyMakeBorder(cells, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
	cv::resize(padded, big, padded.size() * scale, 0, 0, cv::INTER_CUBIC);
	return big(cv::Rect(pad * scale, pad * scale, size, size)).clone();
}

// Calls draw(centre) for every copy of a shape (reaching `reach` texels from its centre) that
// overlaps the texture when it is tiled, so shapes crossing an edge continue on the other side.
template <typename Draw> void draw_wrapped(const cv::Mat &img, cv::Point2d centre, double reach, Draw draw)
{
	const double n = img.cols;
	for (int oy = -1; oy <= 1; oy++) {
		for (int ox = -1; ox <= 1; ox++) {
			const cv::Point2d c = centre + cv::Point2d(ox * n, oy * n);
			if (c.x + reach >= 0 && c.x - reach < n && c.y + reach >= 0 && c.y - reach < n)
				draw(c);
		}
	}
}

// One opaque "leaf" of roughly `scale` texels in a random grey: a rectangle (upright half of
// the time, like most man-made things), ellipse, triangle, ring or bar, the rectangle with the
// texture's own probability. The mix gives straight edges and corners (what FAST and ORB look
// for) as well as curves.
void draw_leaf(cv::Mat &img, double scale, double p_rectangle, cv::RNG &rng)
{
	// One draw per statement: the order of evaluation of function arguments is unspecified, and
	// the texture must not depend on the compiler.
	const double x = rng.uniform(0.0, double(img.cols));
	const cv::Point2d centre(x, rng.uniform(0.0, double(img.rows)));
	const double a = scale * rng.uniform(0.5, 1.0), b = a * rng.uniform(0.25, 1.0);
	const int kind = rng.uniform(0.0, 1.0) < p_rectangle ? 0 : rng.uniform(1, 5);
	const double angle = kind == 0 && rng.uniform(0, 2) ? 0.0 : rng.uniform(0.0, CV_PI);
	const cv::Scalar grey(rng.uniform(8, 248));
	const cv::Point2d ax(std::cos(angle), std::sin(angle)), ay(-ax.y, ax.x);

	draw_wrapped(img, centre, a, [&](cv::Point2d c) {
		switch (kind) {
		case 0: { // rectangle
			const cv::Point corners[4] = {fixed(c + a * ax + b * ay), fixed(c - a * ax + b * ay),
						      fixed(c - a * ax - b * ay), fixed(c + a * ax - b * ay)};
			cv::fillConvexPoly(img, corners, 4, grey, cv::LINE_AA, kShift);
			break;
		}
		case 1: // ellipse
			cv::ellipse(img, fixed(c), cv::Size(cvRound(a * kOne), cvRound(b * kOne)), angle * 180 / CV_PI,
				    0, 360, grey, cv::FILLED, cv::LINE_AA, kShift);
			break;
		case 2: { // triangle
			const cv::Point corners[3] = {fixed(c + a * ax), fixed(c - 0.5 * a * ax + b * ay),
						      fixed(c - 0.3 * a * ax - b * ay)};
			cv::fillConvexPoly(img, corners, 3, grey, cv::LINE_AA, kShift);
			break;
		}
		case 3: // ring
			cv::ellipse(img, fixed(c), cv::Size(cvRound(a * kOne), cvRound(b * kOne)), angle * 180 / CV_PI,
				    0, 360, grey, std::max(1, cvRound(a / 5)), cv::LINE_AA, kShift);
			break;
		default: // bar
			cv::line(img, fixed(c - a * ax), fixed(c + a * ax), grey, std::max(1, cvRound(b / 3)),
				 cv::LINE_AA, kShift);
			break;
		}
	});
}

// Fraction of the area each scale band covers. Later (smaller) bands cover less, so that large
// structure still shows through the small: a quarter of the area keeps leaves of 64 texels
// and more.
double coverage(double scale)
{
	return scale >= 64 ? 0.7 : scale >= 32 ? 0.45 : scale >= 16 ? 0.3 : scale >= 8 ? 0.2 : 0.12;
}

// std::floor and std::log2 become library calls on baseline x86-64 (no SSE4.1), and these two
// sit in the innermost loop.
int floor_int(float x)
{
	const int i = int(x); // truncates towards zero
	return i - (x < float(i));
}

// log2 of x > 0, linear between powers of two (off by at most 0.09): continuous and increasing,
// which is all that choosing a mip level needs.
float log2_approx(float x)
{
	uint32_t bits;
	std::memcpy(&bits, &x, sizeof bits);
	const int exponent = int(bits >> 23) - 127;
	bits = (bits & 0x007fffffu) | 0x3f800000u; // the mantissa, as a float in [1, 2)
	float mantissa;
	std::memcpy(&mantissa, &bits, sizeof mantissa);
	return float(exponent) + mantissa - 1;
}

} // namespace

cv::Mat generate_texture(int size, uint64_t seed)
{
	cv::RNG rng(seed);

	// Large-scale shading so that no two regions are the same flat grey.
	const cv::Mat coarse = value_noise(size, 4, rng);
	const cv::Mat medium = value_noise(size, 16, rng);
	cv::Mat img;
	cv::Mat(128 + 45 * coarse + 25 * medium).convertTo(img, CV_8U);

	// Scale bands from a quarter of the texture down to a few texels, largest first.
	const double p_rectangle = rng.uniform(0.2, 0.7);
	for (double scale = size / 4.0; scale >= 3.0; scale /= 2) {
		const int count = cvRound(coverage(scale) * size * size / (scale * scale));
		for (int i = 0; i < count; i++)
			draw_leaf(img, scale, p_rectangle, rng);
	}

	// Fine grain inside flat leaves, as on any real surface.
	const cv::Mat grain = value_noise(size, size / 4, rng);
	cv::Mat out;
	img.convertTo(img, CV_32F);
	cv::Mat(img + 10 * grain).convertTo(out, CV_8U);
	return out;
}

Texture::Texture(const cv::Mat &base)
{
	CV_Assert(base.type() == CV_8UC1 && base.rows == base.cols && (base.cols & (base.cols - 1)) == 0);
	cv::Mat image = base;
	for (int level = 0;; level++) {
		const int side = image.cols;
		Level l;
		l.texels.resize(size_t(side) * size_t(side));
		l.mask = side - 1;
		l.block_shift = 0;
		while (l.block_shift < 3 && (2 << l.block_shift) <= side)
			l.block_shift++;
		l.row_shift = 0;
		while ((1 << (l.row_shift + l.block_shift)) < side)
			l.row_shift++;
		l.scale = 1.0f / float(1 << level);
		levels_.push_back(std::move(l));
		Level &stored = levels_.back();
		const int b = (1 << stored.block_shift) - 1;
		for (int y = 0; y < side; y++)
			for (int x = 0; x < side; x++)
				stored.texels[size_t(((((y >> stored.block_shift) << stored.row_shift) + (x >> stored.block_shift))
						      << (2 * stored.block_shift)) |
						     ((y & b) << stored.block_shift) | (x & b))] = image.at<uint8_t>(y, x);
		if (side == 1)
			break;
		cv::resize(image, image, image.size() / 2, 0, 0, cv::INTER_AREA);
	}
}

inline float Texture::bilinear(const Level &level, float u, float v) const
{
	// Texel i covers [i, i + 1), so its centre is at i + 0.5.
	const float x = u * level.scale - 0.5f, y = v * level.scale - 0.5f;
	const int ix = floor_int(x), iy = floor_int(y);
	const float ax = x - float(ix), ay = y - float(iy);
	const int x0 = ix & level.mask, y0 = iy & level.mask; // wraps negatives too
	const int x1 = (x0 + 1) & level.mask, y1 = (y0 + 1) & level.mask;
	const float t0 = level.at(x0, y0), t1 = level.at(x1, y0);
	const float b0 = level.at(x0, y1), b1 = level.at(x1, y1);
	const float top = t0 + ax * (t1 - t0), bottom = b0 + ax * (b1 - b0);
	return top + ay * (bottom - top);
}

inline float Texture::trilinear(float u, float v, float lod) const
{
	const int top = int(levels_.size()) - 1;
	if (lod >= float(top))
		return bilinear(levels_[size_t(top)], u, v);
	const int level = int(lod);
	const float w = lod - float(level);
	const float fine = bilinear(levels_[size_t(level)], u, v);
	return w > 0 ? fine + w * (bilinear(levels_[size_t(level) + 1], u, v) - fine) : fine;
}

float Texture::sample(const Footprint &fp) const
{
	// Wrap once in double precision (ground coordinates are world metres over a texel size and
	// can be large), then work in float within one period.
	const double n = levels_[0].mask + 1;
	const float u = float(fp.u - n * std::floor(fp.u / n)), v = float(fp.v - n * std::floor(fp.v / n));

	const float lx2 = float(fp.dudx * fp.dudx + fp.dvdx * fp.dvdx);
	const float ly2 = float(fp.dudy * fp.dudy + fp.dvdy * fp.dvdy);
	const bool x_major = lx2 >= ly2;
	const float major = std::sqrt(x_major ? lx2 : ly2), minor = std::sqrt(x_major ? ly2 : lx2);
	const float du = float(x_major ? fp.dudx : fp.dudy), dv = float(x_major ? fp.dvdx : fp.dvdy);

	// Rounded, not ceiled: a nearly round footprint takes one tap, blurring its short axis a little.
	const int taps = int(std::min(major / std::max(minor, 1e-6f) + 0.5f, float(kMaxTaps)));
	const float width = std::max(minor, major / float(taps));
	const float lod = width > 1.0f ? log2_approx(width) : 0.0f;
	if (taps == 1)
		return trilinear(u, v, lod);

	float sum = 0;
	for (int i = 0; i < taps; i++) {
		const float k = (float(i) + 0.5f) / float(taps) - 0.5f;
		sum += trilinear(u + k * du, v + k * dv, lod);
	}
	return sum / float(taps);
}

} // namespace synth
