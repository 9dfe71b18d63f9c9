/* One function per subcommand, each in cmd_<name>.c. */
#pragma once

int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_simulate(int argc, char **argv);
int cmd_support(int argc, char **argv);
int cmd_intensity(int argc, char **argv);
int cmd_matirf(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_params(int argc, char **argv);
int cmd_report(int argc, char **argv);

/* Shared by subcommands: print "col0rme CMD: error: MSG" and return 1. */
int c0_cli_error(const char *cmd);
/* The same with a command's own parameter names mapped to its flags. */
struct c0_cli_name;
int c0_cli_error_names(const char *cmd, const struct c0_cli_name *names);
