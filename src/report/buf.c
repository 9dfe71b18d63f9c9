/* The page's text: appending, escaping, numbers tagged with their
 * report.json path, and PNG images encoded in memory as base64. */
#include "report/html.h"
#include "core/err.h"

#include <ctype.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int grow(struct c0_html *h, size_t more)
{
	if (h->st)
		return 0;
	if (h->n + more + 1 <= h->cap)
		return 1;
	size_t cap = h->cap ? h->cap : 1 << 16;
	while (cap < h->n + more + 1)
		cap *= 2;
	char *s = realloc(h->s, cap);
	if (!s) {
		h->st = c0_fail(C0_ENOMEM, "report.html: out of memory");
		return 0;
	}
	h->s = s, h->cap = cap;
	return 1;
}

static void add_n(struct c0_html *h, const char *text, size_t n)
{
	if (!grow(h, n))
		return;
	memcpy(h->s + h->n, text, n);
	h->n += n;
	h->s[h->n] = 0;
}

void c0_html_add(struct c0_html *h, const char *text)
{
	add_n(h, text, strlen(text));
}

void c0_html_printf(struct c0_html *h, const char *fmt, ...)
{
	char small[512];
	va_list ap;
	va_start(ap, fmt);
	int n = vsnprintf(small, sizeof small, fmt, ap);
	va_end(ap);
	if (n < 0)
		return;
	if ((size_t)n < sizeof small) {
		add_n(h, small, (size_t)n);
		return;
	}
	if (!grow(h, (size_t)n))
		return;
	va_start(ap, fmt);
	vsnprintf(h->s + h->n, (size_t)n + 1, fmt, ap);
	va_end(ap);
	h->n += (size_t)n;
}

void c0_html_escape(struct c0_html *h, const char *text)
{
	for (const char *p = text; *p; p++) {
		switch (*p) {
		case '&': c0_html_add(h, "&amp;"); break;
		case '<': c0_html_add(h, "&lt;"); break;
		case '>': c0_html_add(h, "&gt;"); break;
		case '"': c0_html_add(h, "&quot;"); break;
		default: add_n(h, p, 1);
		}
	}
}

void c0_html_num(struct c0_html *h, const char *path, double v)
{
	c0_html_printf(h, "<span class=\"num\" data-json=\"%s\">%.4g</span>", path, v);
}

static void base64(struct c0_html *h, const uint8_t *d, size_t n)
{
	static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
	if (!grow(h, (n + 2) / 3 * 4))
		return;
	char *o = h->s + h->n;
	for (size_t i = 0; i < n; i += 3) {
		uint32_t v = (uint32_t)d[i] << 16 | (i + 1 < n ? (uint32_t)d[i + 1] << 8 : 0) | (i + 2 < n ? d[i + 2] : 0);
		*o++ = b64[v >> 18 & 63];
		*o++ = b64[v >> 12 & 63];
		*o++ = i + 1 < n ? b64[v >> 6 & 63] : '=';
		*o++ = i + 2 < n ? b64[v & 63] : '=';
	}
	h->n = (size_t)(o - h->s);
	h->s[h->n] = 0;
}

struct membuf { uint8_t *d; size_t n, cap; int oom; };

static void mem_write(png_structp png, png_bytep data, png_size_t n)
{
	struct membuf *m = png_get_io_ptr(png);
	if (m->oom)
		return;
	if (m->n + n > m->cap) {
		size_t cap = m->cap ? m->cap * 2 : 1 << 14;
		while (cap < m->n + n)
			cap *= 2;
		uint8_t *d = realloc(m->d, cap);
		if (!d) {
			m->oom = 1;
			return;
		}
		m->d = d, m->cap = cap;
	}
	memcpy(m->d + m->n, data, n);
	m->n += n;
}

static void mem_flush(png_structp png)
{
	(void)png;
}

/* The image's colours when there are at most 256 (a hash of 1024 slots),
 * else 0; idx: each pixel's entry in pal. */
static int palette(const uint8_t *rgb, size_t n, png_color *pal, uint8_t *idx)
{
	int32_t slot[1024];
	uint8_t which[1024];
	int np = 0;
	memset(slot, 0xff, sizeof slot);
	for (size_t i = 0; i < n; i++) {
		int32_t c = rgb[3 * i] << 16 | rgb[3 * i + 1] << 8 | rgb[3 * i + 2];
		unsigned h = ((unsigned)c * 2654435761u) >> 22;
		while (slot[h] >= 0 && slot[h] != c)
			h = (h + 1) & 1023;
		if (slot[h] < 0) {
			if (np == 256)
				return 0;
			slot[h] = c, which[h] = (uint8_t)np;
			pal[np++] = (png_color){ rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2] };
		}
		idx[i] = which[h];
	}
	return np;
}

static int all_grey(const uint8_t *rgb, size_t n)
{
	for (size_t i = 0; i < n; i++)
		if (rgb[3 * i] != rgb[3 * i + 1] || rgb[3 * i] != rgb[3 * i + 2])
			return 0;
	return 1;
}

/* libpng into memory: 8-bit grey (grey: idx holds the levels), indexed with
 * np colours (idx), else RGB */
static int png_rows(int w, int ht, const uint8_t *rgb, int grey, const png_color *pal, int np, const uint8_t *idx,
		    struct membuf *m)
{
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!info || setjmp(png_jmpbuf(png))) {
		png_destroy_write_struct(&png, info ? &info : NULL);
		return c0_fail(C0_ENOMEM, "report.html: PNG encoding failed");
	}
	png_set_write_fn(png, m, mem_write, mem_flush);
	png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)ht, 8,
		     grey ? PNG_COLOR_TYPE_GRAY : np ? PNG_COLOR_TYPE_PALETTE : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
		     PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	if (np && !grey)
		png_set_PLTE(png, info, pal, np);
	png_set_compression_level(png, 6);
	png_write_info(png, info);
	for (int y = 0; y < ht; y++)
		png_write_row(png, grey || np ? idx + (size_t)y * w : rgb + (size_t)y * w * 3);
	png_write_end(png, info);
	png_destroy_write_struct(&png, &info);
	return m->oom ? c0_fail(C0_ENOMEM, "report.html: out of memory") : C0_OK;
}

/* as grey when every pixel is (the mean images, the render), indexed when
 * the image has at most 256 colours (the error map's 33 levels): a third
 * of the bytes or less */
static int png_encode(int w, int ht, const uint8_t *rgb, struct membuf *m)
{
	png_color pal[256];
	uint8_t *idx = malloc((size_t)w * ht);
	if (!idx)
		return c0_fail(C0_ENOMEM, "report.html: out of memory");
	const size_t n = (size_t)w * ht;
	const int grey = all_grey(rgb, n);
	int np = 0;
	if (grey)
		for (size_t i = 0; i < n; i++)
			idx[i] = rgb[3 * i];
	else
		np = palette(rgb, n, pal, idx);
	int st = png_rows(w, ht, rgb, grey, pal, np, idx, m);
	free(idx);
	return st;
}

void c0_html_png(struct c0_html *h, int w, int ht, const uint8_t *rgb)
{
	if (h->st)
		return;
	struct membuf m = { 0 };
	int st = png_encode(w, ht, rgb, &m);
	if (st)
		h->st = st;
	else {
		c0_html_add(h, "data:image/png;base64,");
		base64(h, m.d, m.n);
	}
	free(m.d);
}

const cJSON *c0_json_at(const cJSON *root, const char *path)
{
	char key[128];
	const cJSON *o = root;
	while (o && *path) {
		size_t k = strcspn(path, ".");
		if (k >= sizeof key)
			return NULL;
		memcpy(key, path, k);
		key[k] = 0;
		path += k + (path[k] == '.');
		if (cJSON_IsArray(o) && isdigit((unsigned char)key[0]))
			o = cJSON_GetArrayItem(o, atoi(key));
		else
			o = cJSON_IsObject(o) ? cJSON_GetObjectItemCaseSensitive(o, key) : NULL;
	}
	return o;
}

double c0_json_num(const cJSON *root, const char *path, double def)
{
	const cJSON *o = c0_json_at(root, path);
	return cJSON_IsNumber(o) ? o->valuedouble : def;
}
