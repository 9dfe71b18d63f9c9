/* An output directory written as a transaction. Files go into a staging
 * directory beside it (OUTDIR.c0tmp-PID); c0_outdir_commit swaps the staging
 * directory in, so OUTDIR holds either its previous contents or the whole
 * new result, never a mix. A non-empty OUTDIR is refused unless forced, and
 * then replaced as a whole (so it may hold only files). The library installs
 * no signal handler (a host program's signals are its own): the CLI removes
 * the staging directory on SIGINT and SIGTERM itself; staging directories
 * left by a killed run (dead PID) are removed by the next open. */
#pragma once

struct c0_outdir {
	char path[4096];           /* OUTDIR, without trailing slashes */
	char stage[4200];          /* where the files are written until commit */
	int open;
};

/* Checks OUTDIR (not readable, not a directory, not empty without force,
 * parent not writable) and creates the staging directory. */
int c0_outdir_open(struct c0_outdir *o, const char *path, int force);
/* Full path of name inside the staging directory. */
const char *c0_outdir_file(struct c0_outdir *o, const char *name);
/* Moves the staging directory into place (the old OUTDIR, if any, is removed). */
int c0_outdir_commit(struct c0_outdir *o);
/* Removes the staging directory and everything in it. */
void c0_outdir_rollback(struct c0_outdir *o);
/* Commit when st is 0, else roll back; returns the resulting status. */
int c0_outdir_finish(struct c0_outdir *o, int st);
/* Writes a whole buffer as name inside the directory (atomically). */
int c0_write_file_named(struct c0_outdir *o, const char *name, const void *data, unsigned long n);
/* Unlinks every file in dir and dir itself with system calls only:
 * async-signal-safe (the CLI's signal handler calls it on the staging directory). */
void c0_outdir_remove_flat(const char *dir);
/* Refuses a path that is the directory of one of the inputs (NULL entries
 * are skipped): results never land among, or over, the inputs. */
int c0_outdir_check_inputs(const char *path, const char *const *inputs, int n);
