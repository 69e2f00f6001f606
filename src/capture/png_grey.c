#include "capture/png_grey.h"

#include <errno.h>
#include <libdeflate.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "util/kernels.h"

/* Larger than any camera frame (8K is 7680 x 4320), small enough that sizes cannot overflow. */
#define MAX_SIDE 65535
/*
 * 64 Mpixel (8K is 33): the scratch grows to the largest image seen and stays, so a corrupt
 * header claiming 65535 x 65535 must not make it 4 GiB; such a header is left to imdecode,
 * whose own limit (1 Gpixel) and error stand as before this decoder.
 */
#define MAX_PIXELS (1u << 26)

struct mvod_png {
	struct libdeflate_decompressor *inflater;
	uint8_t *idat;  /* the IDAT chunks' data joined: one zlib stream */
	size_t idat_cap;
	uint8_t *raw;   /* inflated rows: a filter byte, then w bytes */
	size_t raw_cap;
	uint8_t *zero;  /* w zero bytes: the row above the first */
	size_t zero_cap;
};

int mvod_png_create(struct mvod_png **out)
{
	struct mvod_png *p = calloc(1, sizeof(*p));
	if (!p)
		return -ENOMEM;
	p->inflater = libdeflate_alloc_decompressor();
	if (!p->inflater) {
		free(p);
		return -ENOMEM;
	}
	*out = p;
	return 0;
}

void mvod_png_destroy(struct mvod_png *p)
{
	if (!p)
		return;
	libdeflate_free_decompressor(p->inflater);
	free(p->idat);
	free(p->raw);
	free(p->zero);
	free(p);
}

static uint32_t be32(const uint8_t *b)
{
	return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
}

int mvod_png_grey_size(const uint8_t *buf, size_t len, int *w, int *h)
{
	static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	/*
	 * The signature, then IHDR: length 13, width, height, depth, colour, method, filter, lace,
	 * and its CRC (join_idat starts after it).
	 */
	if (len < 8 + 12 + 13 || memcmp(buf, sig, 8) || be32(buf + 8) != 13 ||
	    memcmp(buf + 12, "IHDR", 4))
		return -ENOTSUP;
	const uint8_t *ihdr = buf + 16;
	uint32_t width = be32(ihdr), height = be32(ihdr + 4);
	if (width < 1 || height < 1 || width > MAX_SIDE || height > MAX_SIDE ||
	    (uint64_t)width * height > MAX_PIXELS || ihdr[8] != 8 ||
	    ihdr[9] != 0 || ihdr[10] != 0 || ihdr[11] != 0 || ihdr[12] != 0)
		return -ENOTSUP;
	*w = (int)width;
	*h = (int)height;
	return 0;
}

/* *buf grown to at least n bytes (contents not kept); allocates only when the size grows. */
static int reserve(uint8_t **buf, size_t *cap, size_t n)
{
	if (n <= *cap)
		return 0;
	uint8_t *grown = realloc(*buf, n);
	if (!grown)
		return -ENOMEM;
	*buf = grown;
	*cap = n;
	return 0;
}

/*
 * The IDAT chunks' data joined into p->idat, *n bytes. -EINVAL when a chunk runs past the end,
 * there is no IDAT, or the image ends without IEND; -ENOTSUP on a critical chunk other than
 * IDAT and IEND (a palette: not a grey image as this decoder reads it).
 */
static int join_idat(struct mvod_png *p, const uint8_t *buf, size_t len, size_t *n)
{
	size_t at = 8 + 12 + 13; /* past the signature and IHDR */
	*n = 0;
	while (len - at >= 12) {
		size_t size = be32(buf + at);
		const uint8_t *type = buf + at + 4;
		if (size > len - at - 12)
			return -EINVAL;
		if (!memcmp(type, "IEND", 4))
			return *n ? 0 : -EINVAL;
		if (!memcmp(type, "IDAT", 4)) {
			int ret = reserve(&p->idat, &p->idat_cap, *n + size);
			if (ret)
				return ret;
			memcpy(p->idat + *n, buf + at + 8, size);
			*n += size;
		} else if (!(type[0] & 0x20)) { /* upper case: critical */
			return -ENOTSUP;
		}
		at += size + 12;
	}
	return -EINVAL;
}

static uint8_t paeth(uint8_t a, uint8_t b, uint8_t c)
{
	int pa = abs(b - c), pb = abs(a - c), pc = abs(a + b - 2 * c);
	return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/* Row d (w bytes) from its filtered bytes s and the row above, up (PNG's five filters, bpp 1). */
static int unfilter(uint8_t *d, const uint8_t *s, const uint8_t *up, int filter, int w)
{
	switch (filter) {
	case 0:
		memcpy(d, s, (size_t)w);
		return 0;
	case 1:
		mvod_png_sub(d, s, w);
		return 0;
	case 2:
		for (int x = 0; x < w; x++)
			d[x] = (uint8_t)(s[x] + up[x]);
		return 0;
	case 3:
		d[0] = (uint8_t)(s[0] + (up[0] >> 1));
		for (int x = 1; x < w; x++)
			d[x] = (uint8_t)(s[x] + ((d[x - 1] + up[x]) >> 1));
		return 0;
	case 4:
		d[0] = (uint8_t)(s[0] + up[0]);
		for (int x = 1; x < w; x++)
			d[x] = (uint8_t)(s[x] + paeth(d[x - 1], up[x], up[x - 1]));
		return 0;
	default:
		return -EINVAL;
	}
}

int mvod_png_grey_decode(struct mvod_png *p, const uint8_t *buf, size_t len, uint8_t *dst,
			 size_t stride)
{
	int w, h;
	int ret = mvod_png_grey_size(buf, len, &w, &h);
	size_t n, row = (size_t)w + 1;
	if (!ret)
		ret = join_idat(p, buf, len, &n);
	if (!ret)
		ret = reserve(&p->raw, &p->raw_cap, row * (size_t)h);
	if (!ret && !(ret = reserve(&p->zero, &p->zero_cap, (size_t)w)))
		memset(p->zero, 0, (size_t)w);
	if (ret)
		return ret;
	/* NULL for the actual size: the stream must fill the rows exactly. */
	if (libdeflate_zlib_decompress(p->inflater, p->idat, n, p->raw, row * (size_t)h, NULL) !=
	    LIBDEFLATE_SUCCESS)
		return -EINVAL;
	for (int y = 0; y < h && !ret; y++) {
		const uint8_t *s = p->raw + (size_t)y * row;
		const uint8_t *up = y ? dst + (size_t)(y - 1) * stride : p->zero;
		ret = unfilter(dst + (size_t)y * stride, s + 1, up, s[0], w);
	}
	return ret;
}
