"""Running Lightpath from bench scripts."""

import resource
import subprocess


def render_cpu(binary, scene, out, seed, extra):
    """Renders `scene` to `out` on 2 threads without extra AOVs; returns the child's CPU
    seconds (the whole process)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, "render", scene, "-o", out, "--quiet", "--aovs", "none",
                    "--threads", "2", "--seed", str(seed)] + extra,
                   check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
