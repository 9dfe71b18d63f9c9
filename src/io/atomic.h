/* Write-then-rename: outputs appear whole or not at all. */
#pragma once
#include <stddef.h>

/* A temporary name in the same directory as path (so rename is atomic). */
void c0_tmp_name(const char *path, char *out, size_t n);
/* Renames tmp onto path; on failure removes tmp and records the error. */
int c0_commit_file(const char *tmp, const char *path);
/* Writes a whole buffer to path atomically. */
int c0_write_file(const char *path, const void *data, size_t n);
