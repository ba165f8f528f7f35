#!/usr/bin/env python3
"""Checks the farm examples in tests/farm that cannot run here against their published formats.

    check_examples.py SSGI [DIR]      check the examples in DIR (default: this script's folder)
    check_examples.py SSGI --self-test
                                      also break a copy of each example in known ways and
                                      require every break to be caught

SSGI is the built ssgi: each example's ssgi command line may use only options that
`SSGI run --help` lists, and a --progress value must be one the help names.
What is checked, and where each rule comes from:
  ssgi.openjd.yaml   OpenJD jobtemplate-2023-09 (openjd-specifications wiki, Template Schemas;
                     the TASK_CHUNKING extension, RFC 0001): root and step keys, parameter
                     definitions, every {{...}} reference resolves in its scope, CHUNK[INT]
                     chunks, and --frames takes a CONTIGUOUS chunk ("START-END").
  ssgi_opencue.py    pyoutline: a Shell layer whose command uses only the tokens cuebot
                     replaces (DispatchSupportService.java), --frames #FRAMESPEC# (or
                     #IFRAME# with chunk 1), launched with use_pycuerun=False so that cuebot
                     sees the command.
  ssgi.deadline_*    Deadline job and plugin info files for the CommandLine plugin:
                     Plugin=CommandLine, Frames, ChunkSize, Executable, Arguments with
                     <STARTFRAME>-<ENDFRAME> as --frames, only the tokens Deadline replaces.
  ssgi_array.sbatch  the ssgi command line of the Slurm script (tests/farm/slurm_test.sh runs
                     it for real).
Exit status 0 when every check passes, 1 otherwise. Needs python3 and python3-yaml.
"""

import ast
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

import yaml

WORD_VALUED_OPTIONS = {"progress"}  # their value must be a word `ssgi run --help` names


class Checker:
    def __init__(self, help_text):
        self.errors = []
        self.notes = []
        self.help_text = help_text
        # "  -o, --output PATTERN  ..." / "  --skip-missing        ..." / "  --env-up y|z  ..."
        self.long_takes_value = {}
        self.short_to_long = {}
        for m in re.finditer(r"^\s+(?:-(\w), )?--([a-z0-9-]+)( \S+)?(?:\s{2,}|$)", help_text,
                             re.M):
            short, name, arg = m.groups()
            self.long_takes_value[name] = arg is not None
            if short:
                self.short_to_long[short] = name
        if "frames" not in self.long_takes_value or "output" not in self.long_takes_value:
            raise SystemExit("check_examples: cannot read the options of `ssgi run --help`")

    def error(self, where, what):
        self.errors.append("%s: %s" % (where, what))

    def check_ssgi_argv(self, where, argv, frames_ok):
        """argv: the words after the program name. frames_ok(value) -> error text or None."""
        if not argv or argv[0] != "run":
            self.error(where, "the ssgi command is not `ssgi run ...`: %r" % argv[:2])
            return
        positional = []
        seen = {}
        i = 1
        while i < len(argv):
            word = argv[i]
            if word.startswith("--"):
                name, eq, value = word[2:].partition("=")
            elif word.startswith("-") and len(word) == 2:
                name, eq, value = self.short_to_long.get(word[1], "?" + word[1]), "", ""
            else:
                positional.append(word)
                i += 1
                continue
            known = name in self.long_takes_value
            if not known:
                self.error(where, "ssgi run has no option %s" % word)
                i += 1
                continue
            takes_value = self.long_takes_value.get(name, True)
            if takes_value and not eq:
                if i + 1 >= len(argv):
                    self.error(where, "%s needs a value" % word)
                    break
                value = argv[i + 1]
                i += 1
            seen[name] = value
            if name in WORD_VALUED_OPTIONS and not re.search(r"\b%s\b" % re.escape(value),
                                                             self.help_text):
                self.error(where, "--%s %s: the value is not in ssgi run --help" % (name, value))
            i += 1
        if len(positional) != 1:
            self.error(where, "expected one INPUT, got %r" % positional)
        if "output" not in seen:
            self.error(where, "no -o/--output")
        if "frames" not in seen:
            self.error(where, "no --frames: each task must write its own chunk")
        else:
            problem = frames_ok(seen["frames"])
            if problem:
                self.error(where, "--frames %s: %s" % (seen["frames"], problem))

    # Open Job Description ----------------------------------------------------------------

    def check_openjd(self, path):
        where = os.path.basename(path)
        with open(path, encoding="utf-8") as f:
            t = yaml.safe_load(f)
        if not isinstance(t, dict):
            self.error(where, "not a YAML mapping")
            return
        ident = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")
        root_keys = {"specificationVersion", "$schema", "name", "description",
                     "parameterDefinitions", "jobEnvironments", "steps", "extensions"}
        for k in set(t) - root_keys:
            self.error(where, "unknown root key %r" % k)
        if t.get("specificationVersion") != "jobtemplate-2023-09":
            self.error(where, "specificationVersion is %r, not jobtemplate-2023-09" %
                       t.get("specificationVersion"))
        if not isinstance(t.get("name"), str) or not t["name"].strip():
            self.error(where, "no job name")
        extensions = t.get("extensions") or []

        params = {}
        per_type = {
            "STRING": {"minLength", "maxLength"},
            "PATH": {"minLength", "maxLength", "objectType", "dataFlow"},
            "INT": {"minValue", "maxValue"},
            "FLOAT": {"minValue", "maxValue"},
        }
        definitions = t.get("parameterDefinitions") or []
        if not isinstance(definitions, list) or not 1 <= len(definitions) <= 50:
            self.error(where, "parameterDefinitions must be a list of 1 to 50")
            definitions = []
        for p in definitions:
            name, ptype = p.get("name"), p.get("type")
            if not isinstance(name, str) or not ident.match(name):
                self.error(where, "parameter name %r is not an identifier" % name)
                continue
            if name in params:
                self.error(where, "parameter %s defined twice" % name)
            if ptype not in per_type:
                self.error(where, "parameter %s: type %r is not STRING, PATH, INT or FLOAT" %
                           (name, ptype))
                continue
            params[name] = p
            allowed = {"name", "type", "description", "default", "allowedValues",
                       "userInterface"} | per_type[ptype]
            for k in set(p) - allowed:
                self.error(where, "parameter %s: key %r is not allowed for %s" % (name, k, ptype))
            if ptype == "PATH":
                if p.get("objectType", "DIRECTORY") not in ("FILE", "DIRECTORY"):
                    self.error(where, "parameter %s: objectType %r" % (name, p["objectType"]))
                if p.get("dataFlow", "NONE") not in ("NONE", "IN", "OUT", "INOUT"):
                    self.error(where, "parameter %s: dataFlow %r" % (name, p["dataFlow"]))
            if ptype == "INT" and "default" in p:
                try:
                    d = int(p["default"])
                    if ("minValue" in p and d < int(p["minValue"])) or (
                            "maxValue" in p and d > int(p["maxValue"])):
                        self.error(where, "parameter %s: default %d out of range" % (name, d))
                except (TypeError, ValueError):
                    self.error(where, "parameter %s: default %r is not an integer" %
                               (name, p["default"]))

        # Format strings outside the steps: Param.* of PATH type is not available there.
        self.check_refs(where, {k: v for k, v in t.items() if k not in ("steps",)}, params,
                        task_params={}, files=set(), in_script=False)

        steps = t.get("steps")
        if not isinstance(steps, list) or not steps:
            self.error(where, "no steps")
            return
        step_keys = {"name", "description", "dependencies", "stepEnvironments",
                     "hostRequirements", "parameterSpace", "script"}
        names = set()
        ran_ssgi = False
        for step in steps:
            sname = step.get("name")
            swhere = "%s: step %r" % (where, sname)
            if not isinstance(sname, str) or not sname:
                self.error(where, "a step without a name")
            elif sname in names:
                self.error(where, "two steps named %r" % sname)
            names.add(sname)
            for k in set(step) - step_keys:
                self.error(swhere, "unknown key %r" % k)
            task_params = {}
            space = step.get("parameterSpace")
            if space is not None:
                defs = space.get("taskParameterDefinitions")
                if not isinstance(defs, list) or not 1 <= len(defs) <= 16:
                    self.error(swhere, "taskParameterDefinitions must be a list of 1 to 16")
                    defs = []
                for d in defs:
                    dname, dtype = d.get("name"), d.get("type")
                    if not isinstance(dname, str) or not ident.match(dname):
                        self.error(swhere, "task parameter name %r is not an identifier" % dname)
                        continue
                    if dtype not in ("INT", "FLOAT", "STRING", "PATH", "CHUNK[INT]"):
                        self.error(swhere, "task parameter %s: type %r" % (dname, dtype))
                    if "range" not in d:
                        self.error(swhere, "task parameter %s has no range" % dname)
                    if dtype == "CHUNK[INT]":
                        if "TASK_CHUNKING" not in extensions:
                            self.error(swhere, "CHUNK[INT] needs extensions: [TASK_CHUNKING]")
                        chunks = d.get("chunks") or {}
                        if "defaultTaskCount" not in chunks:
                            self.error(swhere, "%s: chunks.defaultTaskCount missing" % dname)
                        if chunks.get("rangeConstraint") not in ("CONTIGUOUS", "NONCONTIGUOUS"):
                            self.error(swhere, "%s: chunks.rangeConstraint %r" %
                                       (dname, chunks.get("rangeConstraint")))
                    task_params[dname] = d
                if sum(d.get("type") == "CHUNK[INT]" for d in task_params.values()) > 1:
                    self.error(swhere, "more than one CHUNK[INT] task parameter")
            script = step.get("script") or {}
            run = (script.get("actions") or {}).get("onRun")
            if not isinstance(run, dict) or not isinstance(run.get("command"), str) or \
                    not run["command"].strip():
                self.error(swhere, "no script.actions.onRun.command")
                continue
            args = run.get("args", [])
            if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
                self.error(swhere, "onRun.args must be a list of strings")
                continue
            files = {f.get("name") for f in script.get("embeddedFiles") or []}
            self.check_refs(swhere, step, params, task_params, files, in_script=True)

            command = run["command"]
            m = re.fullmatch(r"\{\{\s*Param\.(\w+)\s*\}\}", command)
            program = str(params.get(m.group(1), {}).get("default", "")) if m else command
            if os.path.basename(program) == "ssgi":
                ran_ssgi = True

                def frames_ok(value):
                    m = re.fullmatch(r"\{\{\s*Task\.Param\.(\w+)\s*\}\}", value)
                    d = task_params.get(m.group(1)) if m else None
                    if d is None:
                        return "not a task parameter of the step"
                    if d.get("type") == "INT":
                        return None
                    if d.get("type") == "CHUNK[INT]":
                        if (d.get("chunks") or {}).get("rangeConstraint") != "CONTIGUOUS":
                            return ("a NONCONTIGUOUS chunk may read 1-9:2, which --frames "
                                    "does not take; use CONTIGUOUS")
                        return None
                    return "a %s task parameter, not a frame" % d.get("type")

                self.check_ssgi_argv(swhere, args, frames_ok)
        if not ran_ssgi:
            self.error(where, "no step runs ssgi")

    def check_refs(self, where, node, params, task_params, files, in_script):
        builtins = {"Session.WorkingDirectory", "Session.HasPathMappingRules",
                    "Session.PathMappingRulesFile"}
        for text in strings_in(node):
            for ref in re.findall(r"\{\{\s*([^}]*?)\s*\}\}", text):
                m = re.fullmatch(r"(Param|RawParam|Task\.Param|Task\.RawParam|Task\.File|"
                                 r"Env\.File)\.(\w+)", ref)
                kind, name = (m.group(1), m.group(2)) if m else (None, None)
                if ref in builtins and in_script:
                    continue
                if kind in ("Param", "RawParam") and name in params:
                    if kind == "Param" and params[name]["type"] == "PATH" and not in_script:
                        self.error(where, "{{%s}}: a PATH parameter outside a script" % ref)
                    continue
                if kind in ("Task.Param", "Task.RawParam") and name in task_params and in_script:
                    continue
                if kind == "Task.File" and name in files:
                    continue
                self.error(where, "{{%s}} refers to nothing defined here" % ref)

    # OpenCue -----------------------------------------------------------------------------

    CUEBOT_TOKENS = {"#ZFRAME#", "#IFRAME#", "#FRAME_START#", "#FRAME_END#", "#FRAME_CHUNK#",
                     "#LAYER#", "#JOB#", "#FRAMESPEC#", "#FRAME#"}

    def check_opencue(self, path):
        where = os.path.basename(path)
        with open(path, encoding="utf-8") as f:
            tree = ast.parse(f.read(), path)
        shells = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and
                  call_name(n.func).endswith("modules.shell.Shell")]
        launches = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and
                    call_name(n.func) == "outline.cuerun.launch"]
        if len(shells) != 1:
            self.error(where, "expected one outline.modules.shell.Shell layer, found %d" %
                       len(shells))
            return
        if len(launches) != 1:
            self.error(where, "expected one outline.cuerun.launch call, found %d" % len(launches))
        else:
            use = {k.arg: k.value for k in launches[0].keywords}.get("use_pycuerun")
            if not (isinstance(use, ast.Constant) and use.value is False):
                self.error(where, "launch without use_pycuerun=False: cuebot would replace "
                           "the tokens in pycuerun's command, not in the layer's")
        kw = {k.arg: k.value for k in shells[0].keywords}
        for needed in ("command", "range", "chunk"):
            if needed not in kw:
                self.error(where, "the Shell layer has no %s=" % needed)
        command = kw.get("command")
        if not isinstance(command, ast.List):
            self.error(where, "the layer's command is not a list")
            return
        argv = []
        for element in command.elts:
            if isinstance(element, ast.Constant) and isinstance(element.value, str):
                argv.append(element.value)
            else:
                argv.append("<%s>" % ast.unparse(element))
        for word in argv:
            for token in re.findall(r"#[A-Z_]+#", word):
                if token not in self.CUEBOT_TOKENS:
                    self.error(where, "%s is not a token cuebot replaces" % token)
        chunk = kw.get("chunk")
        chunk_one = isinstance(chunk, ast.Constant) and chunk.value == 1

        def frames_ok(value):
            if value == "#FRAMESPEC#":
                return None
            if value == "#IFRAME#":
                return None if chunk_one else "#IFRAME# is the chunk's first frame only"
            if value == "#FRAME_START#-#FRAME_END#":
                return None
            return "not the chunk's frames (#FRAMESPEC#)"

        if os.path.basename(argv[0]) != "ssgi":
            self.error(where, "the layer does not run ssgi: %r" % argv[0])
        self.check_ssgi_argv(where, argv[1:], frames_ok)

    # Deadline ----------------------------------------------------------------------------

    def read_info(self, path):
        where = os.path.basename(path)
        info = {}
        with open(path, encoding="utf-8-sig") as f:
            for number, line in enumerate(f, 1):
                line = line.rstrip("\r\n")
                if not line.strip():
                    continue
                key, eq, value = line.partition("=")
                if not eq or not key.strip():
                    self.error(where, "line %d is not KEY=VALUE: %r" % (number, line))
                    continue
                if key in info:
                    self.error(where, "%s given twice" % key)
                info[key] = value
        return info

    def check_deadline(self, job_path, plugin_path):
        jwhere, pwhere = os.path.basename(job_path), os.path.basename(plugin_path)
        job, plugin = self.read_info(job_path), self.read_info(plugin_path)
        if job.get("Plugin") != "CommandLine":
            self.error(jwhere, "Plugin=%s, not CommandLine" % job.get("Plugin"))
        for key in ("Name", "Frames", "ChunkSize"):
            if not job.get(key, "").strip():
                self.error(jwhere, "no %s" % key)
        if job.get("Frames") and not re.fullmatch(r"-?\d+(-?-\d+)?(x\d+)?(,-?\d+(-?-\d+)?(x\d+)?)*",
                                                  job["Frames"].replace(" ", "")):
            self.error(jwhere, "Frames=%s is not a frame list" % job["Frames"])
        if not re.fullmatch(r"[1-9]\d*", job.get("ChunkSize", "")):
            self.error(jwhere, "ChunkSize=%s is not a positive integer" % job.get("ChunkSize"))
        keys = {"Executable", "Arguments", "StartupDirectory", "Shell", "ShellExecute",
                "SingleFramesOnly"}
        for k in set(plugin) - keys:
            self.error(pwhere, "%s is not a CommandLine plugin setting" % k)
        if os.path.basename(plugin.get("Executable", "").strip()) != "ssgi":
            self.error(pwhere, "Executable=%s is not ssgi" % plugin.get("Executable"))
        arguments = plugin.get("Arguments", "")
        for token in re.findall(r"<[^<>]*>", arguments):
            if not re.fullmatch(r"<(STARTFRAME|ENDFRAME)(%\d+)?>|<QUOTE>|<AUXFILE\d+>", token):
                self.error(pwhere, "%s is not a token Deadline replaces" % token)
        for token in ("<STARTFRAME", "<ENDFRAME"):
            if token not in arguments:
                self.error(pwhere, "Arguments without %s>" % token)

        def frames_ok(value):
            if re.fullmatch(r"<STARTFRAME(%\d+)?>-<ENDFRAME(%\d+)?>", value):
                return None
            return "not the task's frames (<STARTFRAME>-<ENDFRAME>)"

        self.check_ssgi_argv(pwhere, shlex.split(arguments.replace("<QUOTE>", '"')), frames_ok)

    # Slurm -------------------------------------------------------------------------------

    def check_sbatch(self, path):
        where = os.path.basename(path)
        with open(path, encoding="utf-8") as f:
            lines = [l for l in f if re.match(r'\s*exec "\$\{SSGI:-ssgi\}" ', l)]
        if len(lines) != 1:
            self.error(where, 'expected one line `exec "${SSGI:-ssgi}" run ...`')
            return
        argv = shlex.split(lines[0])[2:]

        def frames_ok(value):
            return None if value == "$start-$end" else "not the task's chunk ($start-$end)"

        self.check_ssgi_argv(where, argv, frames_ok)

    def check_dir(self, folder):
        self.check_openjd(os.path.join(folder, "ssgi.openjd.yaml"))
        self.check_opencue(os.path.join(folder, "ssgi_opencue.py"))
        self.check_deadline(os.path.join(folder, "ssgi.deadline_job_info.txt"),
                            os.path.join(folder, "ssgi.deadline_plugin_info.txt"))
        self.check_sbatch(os.path.join(folder, "ssgi_array.sbatch"))


def call_name(func):
    if isinstance(func, ast.Attribute):
        return call_name(func.value) + "." + func.attr
    if isinstance(func, ast.Name):
        return func.id
    return ""


def strings_in(node):
    if isinstance(node, str):
        yield node
    elif isinstance(node, dict):
        for k, v in node.items():
            yield from strings_in(k)
            yield from strings_in(v)
    elif isinstance(node, list):
        for v in node:
            yield from strings_in(v)


# Breaks the self-test makes in a copy of the examples: (file, text, replacement, what).
MUTATIONS = [
    ("ssgi.openjd.yaml", "specificationVersion: jobtemplate-2023-09",
     "specificationVersion: jobtemplate-2024-01", "wrong specification version"),
    ("ssgi.openjd.yaml", '"{{Task.Param.Frame}}"', '"{{Task.Param.Frames}}"',
     "a task parameter that does not exist"),
    ("ssgi.openjd.yaml", "{{Param.OutputDir}}/", "{{Param.OutDir}}/",
     "a job parameter that does not exist"),
    ("ssgi.openjd.yaml", "rangeConstraint: CONTIGUOUS", "rangeConstraint: NONCONTIGUOUS",
     "chunks --frames cannot read"),
    ("ssgi.openjd.yaml", "  - TASK_CHUNKING\n", "", "CHUNK[INT] without the extension"),
    ("ssgi.openjd.yaml", "        onRun:\n          command:", "        onRun:\n          cmd:",
     "no onRun.command"),
    ("ssgi.openjd.yaml", "            - --frames\n", "            - --frame\n",
     "an option ssgi run does not have"),
    ("ssgi.openjd.yaml", "    type: INT\n    default: 10", "    type: NUMBER\n    default: 10",
     "a parameter type OpenJD does not have"),
    ("ssgi.openjd.yaml", 'name: "ssgi {{Param.InputName}}', 'name: "ssgi {{Param.InputDir}}',
     "a PATH parameter in the job name"),
    ("ssgi_opencue.py", '"#FRAMESPEC#"', '"#FRAMES#"', "a token cuebot does not replace"),
    ("ssgi_opencue.py", '"#FRAMESPEC#"', '"#IFRAME#"', "#IFRAME# with chunks"),
    ("ssgi_opencue.py", "launch(job, use_pycuerun=False)", "launch(job, use_pycuerun=True)",
     "pycuerun hides the tokens"),
    ("ssgi_opencue.py", '"-o",', '"--out",', "an option ssgi run does not have"),
    ("ssgi.deadline_job_info.txt", "Plugin=CommandLine", "Plugin=CommandScript",
     "another plugin"),
    ("ssgi.deadline_job_info.txt", "ChunkSize=10\n", "", "no ChunkSize"),
    ("ssgi.deadline_plugin_info.txt", "<ENDFRAME>", "<LASTFRAME>", "a token Deadline lacks"),
    ("ssgi.deadline_plugin_info.txt", " --frames ", " --frame-list ",
     "an option ssgi run does not have"),
    ("ssgi.deadline_plugin_info.txt", "Executable=", "Program=", "no Executable"),
    ("ssgi_array.sbatch", '--frames "$start-$end"', '--frames "$start"',
     "one frame per task instead of the chunk"),
    ("ssgi_array.sbatch", '-o "$output"', '--outptu "$output"', "a misspelt option"),
]


def self_test(help_text, folder):
    failures = 0
    for name, text, replacement, what in MUTATIONS:
        with tempfile.TemporaryDirectory() as tmp:
            for f in os.listdir(folder):
                if os.path.isfile(os.path.join(folder, f)):
                    shutil.copy(os.path.join(folder, f), tmp)
            path = os.path.join(tmp, name)
            with open(path, encoding="utf-8") as f:
                content = f.read()
            if text not in content:
                print("check_examples: self-test: %r not found in %s" % (text, name))
                failures += 1
                continue
            with open(path, "w", encoding="utf-8") as f:
                f.write(content.replace(text, replacement, 1))
            checker = Checker(help_text)
            checker.check_dir(tmp)
            if checker.errors:
                print("check_examples: self-test: %s (%s) caught: %s" %
                      (name, what, checker.errors[0]))
            else:
                print("check_examples: self-test: %s (%s) NOT caught" % (name, what))
                failures += 1
    return failures


def main(argv):
    if len(argv) not in (2, 3):
        raise SystemExit(__doc__)
    ssgi = argv[1]
    folder = os.path.dirname(os.path.abspath(__file__))
    run_self_test = len(argv) == 3 and argv[2] == "--self-test"
    if len(argv) == 3 and not run_self_test:
        folder = argv[2]
    help_text = subprocess.run([ssgi, "run", "--help"], check=True, capture_output=True,
                               text=True).stdout
    checker = Checker(help_text)
    checker.check_dir(folder)
    for note in checker.notes:
        print("check_examples: note: " + note)
    for error in checker.errors:
        print("check_examples: FAIL: " + error)
    failures = len(checker.errors)
    if run_self_test:
        failures += self_test(help_text, folder)
    if failures:
        return 1
    print("check_examples: the OpenJD, OpenCue, Deadline and Slurm examples in %s pass%s" %
          (folder, " and every break of the self-test is caught" if run_self_test else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
