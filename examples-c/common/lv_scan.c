/* The examples' near-field scan; see lv_scan.h. */
#include "lv_scan.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

static bool file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0;
}

static bool make_dir(const char *dir) {
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return true;
        fprintf(stderr, "lv_scan: %s exists and is not a directory\n", dir);
        return false;
    }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "lv_scan: cannot create %s: %s\n", dir, strerror(errno));
        return false;
    }
    return true;
}

/* Runs argv[0] with argv and this process's environment minus LD_PRELOAD; true on exit status 0. */
static bool run_tool(char *const argv[]) {
    size_t n = 0;
    while (environ && environ[n]) n++;
    char **env = calloc(n + 1, sizeof *env);
    if (!env) {
        fprintf(stderr, "lv_scan: out of memory\n");
        return false;
    }
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (strncmp(environ[i], "LD_PRELOAD=", 11) != 0) env[k++] = environ[i];
    env[k] = NULL;
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "lv_scan: fork failed: %s\n", strerror(errno));
        free(env);
        return false;
    }
    if (pid == 0) {
        execve(argv[0], argv, env);
        fprintf(stderr, "lv_scan: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    free(env);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) {
            fprintf(stderr, "lv_scan: waitpid failed: %s\n", strerror(errno));
            return false;
        }
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        fprintf(stderr, "lv_scan: %s exited with status %d\n", argv[0], WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        return false;
    }
    return true;
}

/* Generates `final` by running the tool with `tmp` as its output, then renames tmp → final. */
static bool generate(char *const argv[], const char *tmp, const char *final) {
    printf("lv_scan: generating %s (first run):", final);
    for (int i = 0; argv[i]; i++) printf(" %s", argv[i]);
    printf("\n");
    if (!run_tool(argv)) {
        remove(tmp);
        return false;
    }
    if (rename(tmp, final) != 0) {
        fprintf(stderr, "lv_scan: cannot rename %s to %s: %s\n", tmp, final, strerror(errno));
        remove(tmp);
        return false;
    }
    return true;
}

bool lv_scan_ensure(const char *repo_root, lv_scan_files *out) {
    char target[4096], dir[4096], cli[4096], tmp[4200];
    int a = snprintf(target, sizeof target, "%s/target", repo_root);
    int b = snprintf(dir, sizeof dir, "%s/target/nearfield-demo", repo_root);
    int c = snprintf(out->pack, sizeof out->pack, "%s/%s-%s-%s.lvpack", dir, LV_SCAN_LUMINAIRE, LV_SCAN_LAYOUT,
                     LV_SCAN_SIZE);
    int d = snprintf(out->proxy, sizeof out->proxy, "%s/%s-proxy.glb", dir, LV_SCAN_LUMINAIRE);
    /* $LUMIVIEW_CLI, else the installed package's CLI (examples built with find_package), else the
     * debug CLI, else the release one (after only `cargo build --release`). */
    const char *env_cli = getenv("LUMIVIEW_CLI");
#ifdef LUMIVIEW_CLI_PATH
    if (!(env_cli && env_cli[0])) env_cli = LUMIVIEW_CLI_PATH;
#endif
    int e = env_cli && env_cli[0] ? snprintf(cli, sizeof cli, "%s", env_cli)
                                  : snprintf(cli, sizeof cli, "%s/target/debug/lumiview", repo_root);
    if (!(env_cli && env_cli[0]) && e >= 0 && (size_t)e < sizeof cli && access(cli, X_OK) != 0)
        e = snprintf(cli, sizeof cli, "%s/target/release/lumiview", repo_root);
    if (a < 0 || b < 0 || c < 0 || d < 0 || e < 0 || (size_t)a >= sizeof target || (size_t)b >= sizeof dir ||
        (size_t)c >= sizeof out->pack || (size_t)d >= sizeof out->proxy || (size_t)e >= sizeof cli) {
        fprintf(stderr, "lv_scan: paths under %s are too long\n", repo_root);
        return false;
    }
    /* ':' in the layout is fine in a file name on POSIX, but keep names plain. */
    for (char *p = strrchr(out->pack, '/'); p && *p; p++)
        if (*p == ':') *p = '_';
    bool need_pack = !file_exists(out->pack), need_proxy = !file_exists(out->proxy);
    if (!need_pack && !need_proxy) return true;
    if (access(cli, X_OK) != 0) {
        fprintf(stderr, "lv_scan: the near-field scan %s is not there yet and the lumiview CLI %s cannot be run "
                        "(%s): build it with `cargo build --release` or `cargo build --bin lumiview`, or set LUMIVIEW_CLI\n",
                out->pack, cli, strerror(errno));
        return false;
    }
    if (!make_dir(target) || !make_dir(dir)) return false;
    if (need_pack) {
        snprintf(tmp, sizeof tmp, "%s.tmp%ld.lvpack", out->pack, (long)getpid());
        char *argv[] = {cli, "pack", "--synth", LV_SCAN_LUMINAIRE, "--layout", LV_SCAN_LAYOUT, "--size", LV_SCAN_SIZE,
                        "--no-proxy", "--quiet", "-o", tmp, NULL};
        if (!generate(argv, tmp, out->pack)) return false;
    }
    if (need_proxy) {
        snprintf(tmp, sizeof tmp, "%s.tmp%ld.glb", out->proxy, (long)getpid());
        char *argv[] = {cli, "synth", LV_SCAN_LUMINAIRE, "--proxy", tmp, NULL};
        if (!generate(argv, tmp, out->proxy)) return false;
    }
    return true;
}

const char *lv_selection_name(uint32_t mode) {
    switch (mode) {
    case LUMI_SELECTION_NEAREST: return "nearest";
    case LUMI_SELECTION_IDW4: return "idw4";
    case LUMI_SELECTION_CONTINUOUS: return "continuous";
    default: return "unknown";
    }
}

bool lv_parse_selection(const char *s, uint32_t *mode) {
    static const uint32_t modes[] = {LUMI_SELECTION_NEAREST, LUMI_SELECTION_IDW4, LUMI_SELECTION_CONTINUOUS};
    for (size_t i = 0; s && i < sizeof modes / sizeof modes[0]; i++) {
        if (strcmp(s, lv_selection_name(modes[i])) == 0) {
            *mode = modes[i];
            return true;
        }
    }
    return false;
}
