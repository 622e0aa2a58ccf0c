"""The README's Python example runs as written and prints what its last
comment says."""

import contextlib
import io
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_readme_python_example_prints_what_it_says():
    readme = (ROOT / "README.md").read_text()
    examples = readme[readme.index("## Examples"):]
    code = re.search(r"```python\n(.*?)```", examples, re.S).group(1)
    said = code.rstrip().splitlines()[-1].rsplit("# ", 1)[1].strip()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    assert out.getvalue().strip() == said
