#include "io/imagej.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void c0_unit_normalise(const char *in, char out[16])
{
	static const struct { const char *spell, *unit; } map[] = {
		{ "nm", "nm" }, { "nanometer", "nm" }, { "nanometre", "nm" },
		{ "um", "um" }, { "micron", "um" }, { "microns", "um" }, { "\xc2\xb5m", "um" },
		{ "\xb5m", "um" }, { "\\u00B5m", "um" }, { "\\u00b5m", "um" }, { "micrometer", "um" },
		{ "micrometre", "um" }, { "mm", "mm" }, { "cm", "cm" }, { "inch", "inch" },
	};
	out[0] = '\0';
	for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
		if (!strcmp(in, map[i].spell)) {
			snprintf(out, 16, "%s", map[i].unit);
			return;
		}
}

double c0_unit_nm(const char *unit)
{
	if (!strcmp(unit, "nm")) return 1;
	if (!strcmp(unit, "um")) return 1e3;
	if (!strcmp(unit, "mm")) return 1e6;
	if (!strcmp(unit, "cm")) return 1e7;
	if (!strcmp(unit, "inch")) return 2.54e7;
	return 0;
}

/* Value of "key=" at the start of a line, copied into val. */
static int ij_value(const char *desc, const char *key, char *val, size_t n)
{
	size_t kl = strlen(key);
	for (const char *p = desc; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL) {
		if (!strncmp(p, key, kl) && p[kl] == '=') {
			const char *v = p + kl + 1;
			size_t l = strcspn(v, "\r\n");
			if (l >= n)
				l = n - 1;
			memcpy(val, v, l);
			val[l] = '\0';
			return 1;
		}
	}
	return 0;
}

static int64_t ij_int(const char *desc, const char *key)
{
	char v[32];
	if (!ij_value(desc, key, v, sizeof v))
		return 0;
	long long x = strtoll(v, NULL, 10);
	return x > 0 ? x : 0;
}

static double ij_double(const char *desc, const char *key)
{
	char v[64];
	return ij_value(desc, key, v, sizeof v) ? strtod(v, NULL) : 0;
}

void c0_ij_parse(const char *desc, struct c0_ij_meta *m)
{
	memset(m, 0, sizeof *m);
	m->channels = m->slices = m->frames = 1;
	if (!desc || strncmp(desc, "ImageJ=", 7))
		return;
	m->present = 1;
	m->images = ij_int(desc, "images");
	int64_t c = ij_int(desc, "channels"), z = ij_int(desc, "slices"), t = ij_int(desc, "frames");
	m->channels = c ? c : 1;
	m->slices = z ? z : 1;
	m->frames = t ? t : 1;
	char u[64];
	if (ij_value(desc, "unit", u, sizeof u))
		c0_unit_normalise(u, m->unit);
	m->spacing = ij_double(desc, "spacing");
	m->finterval = ij_double(desc, "finterval");
}

/* Attribute value attr="..." in xml after position p. */
static int xml_attr(const char *xml, const char *attr, char *val, size_t n)
{
	char pat[80];
	if (snprintf(pat, sizeof pat, " %s=\"", attr) >= (int)sizeof pat)
		return 0;
	const char *p = strstr(xml, pat);
	if (!p)
		return 0;
	p += strlen(pat);
	size_t l = strcspn(p, "\"");
	if (l >= n)
		l = n - 1;
	memcpy(val, p, l);
	val[l] = '\0';
	return 1;
}

static double ome_length_nm(const char *xml, const char *attr)
{
	char v[64], ua[80], u[64], nu[16];
	if (!xml_attr(xml, attr, v, sizeof v))
		return 0;
	snprintf(ua, sizeof ua, "%sUnit", attr);
	if (!xml_attr(xml, ua, u, sizeof u))
		snprintf(u, sizeof u, "um");     /* the OME schema default is µm */
	c0_unit_normalise(u, nu);
	double s = strtod(v, NULL) * c0_unit_nm(nu);
	return s > 0 ? s : 0;
}

double c0_ome_pixel_size_nm(const char *xml, double *z_nm)
{
	if (!xml || !strstr(xml, "<OME"))
		return 0;
	if (z_nm)
		*z_nm = ome_length_nm(xml, "PhysicalSizeZ");
	return ome_length_nm(xml, "PhysicalSizeX");
}

int c0_ome_layout(const char *xml, struct c0_ome_layout *l)
{
	memset(l, 0, sizeof *l);
	if (!xml || !strstr(xml, "<OME"))
		return 0;
	char v[32], order[16];
	l->size_c = xml_attr(xml, "SizeC", v, sizeof v) ? strtoll(v, NULL, 10) : 1;
	l->size_z = xml_attr(xml, "SizeZ", v, sizeof v) ? strtoll(v, NULL, 10) : 1;
	l->size_t_ = xml_attr(xml, "SizeT", v, sizeof v) ? strtoll(v, NULL, 10) : 1;
	if (!xml_attr(xml, "DimensionOrder", order, sizeof order))
		snprintf(order, sizeof order, "XYCZT");
	if (l->size_c < 1 || l->size_z < 1 || l->size_t_ < 1 || l->size_c > 4096 || l->size_z > (1 << 30) || l->size_t_ > (1 << 30))
		return 0;
	/* the channel's stride: the product of the sizes of the axes before C */
	l->stride_c = 1;
	for (const char *a = order + 2; *a && *a != 'C'; a++)
		l->stride_c *= *a == 'Z' ? l->size_z : *a == 'T' ? l->size_t_ : 1;
	l->series = 0;
	for (const char *p = xml; (p = strstr(p, "<Image ")); p++)
		l->series++;
	if (l->series < 1)
		l->series = 1;
	return 1;
}

int c0_ij_format(char *buf, size_t n, int64_t channels, int64_t slices, int64_t frames,
		 int calibrated, double z_spacing_um, double finterval_s, double dmin, double dmax)
{
	int64_t images = channels * slices * frames;
	size_t k = 0;
	int w;
#define PUT(...) do { w = snprintf(buf + k, n - k, __VA_ARGS__); if (w < 0 || (size_t)w >= n - k) return -1; k += w; } while (0)
	PUT("ImageJ=1.11a\nimages=%lld\n", (long long)images);
	if (channels > 1) PUT("channels=%lld\n", (long long)channels);
	if (slices > 1) PUT("slices=%lld\n", (long long)slices);
	if (frames > 1) PUT("frames=%lld\n", (long long)frames);
	if (images > 1 && (channels > 1) + (slices > 1) + (frames > 1) > 1) PUT("hyperstack=true\n");
	if (channels > 1) PUT("mode=grayscale\n");
	if (calibrated) PUT("unit=um\n");
	if (z_spacing_um > 0) PUT("spacing=%.9g\n", z_spacing_um);
	if (finterval_s > 0) PUT("finterval=%.9g\n", finterval_s);
	PUT("loop=false\n");
	if (dmin != 0 || dmax != 0) PUT("min=%.9g\nmax=%.9g\n", dmin, dmax);
#undef PUT
	return (int)k;
}

int c0_ij_append(char *buf, size_t n, int len, const char *key, double value)
{
	if (len < 0 || (size_t)len >= n)
		return -1;
	int w = snprintf(buf + len, n - (size_t)len, "%s=%.9g\n", key, value);
	return w < 0 || (size_t)w >= n - (size_t)len ? -1 : len + w;
}
