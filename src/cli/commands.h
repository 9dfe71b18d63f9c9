/* One function per subcommand, each in cmd_<name>.c. */
#pragma once

int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_simulate(int argc, char **argv);
int cmd_support(int argc, char **argv);
int cmd_intensity(int argc, char **argv);
int cmd_matirf(int argc, char **argv);
int cmd_run(int argc, char **argv);

/* Shared by subcommands: print "col0rme CMD: error: MSG" and return 1. */
int c0_cli_error(const char *cmd);
