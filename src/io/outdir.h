/* An output directory that commands fill file by file. It refuses a
 * non-empty directory unless forced, and on failure removes what this run
 * wrote (and the directory, if this run created it). */
#pragma once

struct c0_outdir {
	char path[4096];
	int created;
	int nfiles;
	char files[64][256];
};

int c0_outdir_open(struct c0_outdir *o, const char *path, int force);
/* Full path of name inside the directory, recorded for cleanup. */
const char *c0_outdir_file(struct c0_outdir *o, const char *name);
void c0_outdir_rollback(struct c0_outdir *o);
/* Writes a whole buffer as name inside the directory (atomically). */
int c0_write_file_named(struct c0_outdir *o, const char *name, const void *data, unsigned long n);
/* Refuses a path that is the directory of one of the inputs (NULL entries
 * are skipped): results never land among, or over, the inputs. */
int c0_outdir_check_inputs(const char *path, const char *const *inputs, int n);
