#include "capture/image_header.h"

#include <errno.h>
#include <limits.h>
#include <stdbool.h>
#include <string.h>

static uint32_t be16(const uint8_t *p)
{
	return (uint32_t)p[0] << 8 | p[1];
}

static uint32_t be32(const uint8_t *p)
{
	return be16(p) << 16 | be16(p + 2);
}

static uint32_t le16(const uint8_t *p)
{
	return (uint32_t)p[1] << 8 | p[0];
}

static uint32_t le32(const uint8_t *p)
{
	return le16(p + 2) << 16 | le16(p);
}

/* w x h as the caller's ints: both 1 .. INT_MAX, else -EINVAL. */
static int size_of(int64_t w, int64_t h, int *ow, int *oh)
{
	if (w < 1 || h < 1 || w > INT_MAX || h > INT_MAX)
		return -EINVAL;
	*ow = (int)w;
	*oh = (int)h;
	return 0;
}

/* PNG: the signature, then the IHDR chunk, whose first fields are width and height. */
static int png_size(const uint8_t *b, size_t len, int *w, int *h)
{
	if (len < 24 || memcmp(b + 12, "IHDR", 4) != 0)
		return -EINVAL;
	return size_of(be32(b + 16), be32(b + 20), w, h);
}

/* A marker of a start of frame: SOF0 .. SOF15 but DHT (C4), JPG (C8) and DAC (CC). */
static bool jpeg_sof(uint8_t m)
{
	return m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
}

/* JPEG: segments from SOI, each skipped by its length, up to the first start of frame. */
static int jpeg_size(const uint8_t *b, size_t len, int *w, int *h)
{
	size_t i = 2;
	while (i + 4 <= len) {
		if (b[i] != 0xFF)
			return -EINVAL;
		uint8_t m = b[i + 1];
		if (m == 0xFF) { /* fill byte before a marker */
			i++;
			continue;
		}
		if (m == 0x01 || (m >= 0xD0 && m <= 0xD8)) { /* markers without a length */
			i += 2;
			continue;
		}
		if (m == 0xD9 || m == 0xDA) /* the end, or the scan, before any frame */
			return -EINVAL;
		if (jpeg_sof(m))
			return i + 9 <= len ? size_of(be16(b + i + 7), be16(b + i + 5), w, h)
					    : -EINVAL;
		i += 2 + be16(b + i + 2);
	}
	return -EINVAL;
}

/* The next decimal number of a PNM header at *i, past blanks and '#' comments; -1 if none. */
static int64_t pnm_number(const uint8_t *b, size_t len, size_t *i)
{
	for (;;) {
		while (*i < len && strchr(" \t\r\n\v\f", b[*i]) && b[*i])
			(*i)++;
		if (*i >= len || b[*i] != '#')
			break;
		while (*i < len && b[*i] != '\n')
			(*i)++;
	}
	int64_t v = -1;
	for (int digits = 0; *i < len && b[*i] >= '0' && b[*i] <= '9'; (*i)++, digits++)
		v = digits >= 10 ? INT64_MAX : (v < 0 ? 0 : 10 * v) + (b[*i] - '0');
	return v;
}

/* PNM, P1 to P6: magic, width and height as decimal text. */
static int pnm_size(const uint8_t *b, size_t len, int *w, int *h)
{
	size_t i = 2;
	int64_t width = pnm_number(b, len, &i);
	return size_of(width, pnm_number(b, len, &i), w, h);
}

/* BMP: the info header after the 14-byte file header; a negative height is top-down. */
static int bmp_size(const uint8_t *b, size_t len, int *w, int *h)
{
	if (len < 26)
		return -EINVAL;
	if (le32(b + 14) == 12) /* BITMAPCOREHEADER: 16-bit sizes */
		return size_of(le16(b + 18), le16(b + 20), w, h);
	int32_t height = (int32_t)le32(b + 22);
	return size_of((int32_t)le32(b + 18), height < 0 ? -(int64_t)height : height, w, h);
}

/* TIFF: the first image file directory's ImageWidth (256) and ImageLength (257). */
static int tiff_size(const uint8_t *b, size_t len, int *w, int *h)
{
	bool le = b[0] == 'I';
	uint32_t (*u16)(const uint8_t *) = le ? le16 : be16;
	uint32_t (*u32)(const uint8_t *) = le ? le32 : be32;
	size_t ifd = u32(b + 4);
	if (ifd > len || len - ifd < 2)
		return -EINVAL;
	int64_t width = -1, height = -1;
	uint32_t n = u16(b + ifd);
	for (uint32_t k = 0; k < n && ifd + 2 + 12 * (size_t)(k + 1) <= len; k++) {
		const uint8_t *e = b + ifd + 2 + 12 * (size_t)k;
		uint32_t tag = u16(e), type = u16(e + 2);
		int64_t v = type == 3 ? (int64_t)u16(e + 8) : -1;
		v = type == 4 ? (int64_t)u32(e + 8) : v;
		if (tag == 256)
			width = v;
		if (tag == 257)
			height = v;
	}
	return size_of(width, height, w, h);
}

int mvod_image_header_size(const uint8_t *b, size_t len, int *w, int *h)
{
	if (len >= 8 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0)
		return png_size(b, len, w, h);
	if (len >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF)
		return jpeg_size(b, len, w, h);
	if (len >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6')
		return pnm_size(b, len, w, h);
	if (len >= 2 && b[0] == 'B' && b[1] == 'M')
		return bmp_size(b, len, w, h);
	if (len >= 8 && (memcmp(b, "II*\0", 4) == 0 || memcmp(b, "MM\0*", 4) == 0))
		return tiff_size(b, len, w, h);
	return -EINVAL;
}
