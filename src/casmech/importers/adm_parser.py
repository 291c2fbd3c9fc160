"""Adams/Solver dataset (.adm) text -> statements with line numbers and comments.

The dataset grammar used here (Adams/Solver "Formatting Statements"):

- line 1 is the title; every other line is a statement, a continuation or a comment;
- a statement starts with its name, a slash and an identifier: `PART/02, MASS = 1`;
- a line starting with `,` continues the statement above (comment lines may come between);
- `!` starts a comment (whole line or the rest of a line); `END` ends the dataset;
- arguments are separated by commas: `KEY = v1, v2, v3` (a list), `KEY` alone (a flag);
  `FUNCTION = ...` takes the rest of the statement, continuation commas removed.

Keys and flags are upper-cased; columns are 1-based character positions in the raw line.
"""

from __future__ import annotations

import re
from dataclasses import field

from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source

_HEAD = re.compile(r"\s*([A-Za-z_]+)\s*/\s*([^,]*)")


@record
class Value:
    text: str
    line: int
    col: int


@record(frozen=False)
class Argument:
    key: str  # upper case; for a flag, the flag itself
    values: list[Value] = field(default_factory=list)
    line: int = 0
    col: int = 0


@record(frozen=False)
class Statement:
    name: str  # upper case, e.g. PART
    ident: str  # the text after the slash ("" for UNITS/, ACCGRAV/)
    line: int  # 1-based line of the statement name
    arguments: list[Argument] = field(default_factory=list)
    comments: list[str] = field(default_factory=list)  # comment lines just above it
    text: list[str] = field(default_factory=list)  # the raw lines (for warnings)

    @property
    def label(self) -> str:
        return f"{self.name}/{self.ident}" if self.ident else f"{self.name}/"

    def find(self, *keys: str) -> Argument | None:
        """The argument written with one of `keys` (spellings of one keyword)."""
        for argument in self.arguments:
            if argument.key in keys:
                return argument
        return None

    def flags(self) -> list[Argument]:
        return [a for a in self.arguments if not a.values]


@record(frozen=False)
class Dataset:
    file: str
    title: str
    statements: list[Statement]
    trailing_comments: list[str]


def _split(text: str, start_col: int) -> list[tuple[str, int]]:
    """Comma-separated pieces of `text` at parenthesis depth 0, with their 1-based columns."""
    pieces, depth, begin = [], 0, 0
    for k, char in enumerate(text + ","):
        depth += {"(": 1, ")": -1}.get(char, 0)
        if char == "," and depth == 0:
            piece = text[begin:k]
            stripped = piece.lstrip()
            pieces.append((stripped.rstrip(), start_col + begin + len(piece) - len(stripped)))
            begin = k + 1
    return pieces


def _code_and_comment(line: str) -> tuple[str, str | None]:
    code, bang, comment = line.partition("!")
    return code.rstrip(), comment.strip() if bang else None


class _Builder:
    def __init__(self, file: str):
        self.file = file
        self.statements: list[Statement] = []
        self.pending: list[str] = []
        self.function: Argument | None = None  # a FUNCTION argument still collecting text

    def error(self, line: int, col: int, message: str, expected: str, hint: str) -> ModelError:
        return ModelError([Diagnostic("E102", "", message, Source(self.file, line, col),
                                      expected=expected, hint=hint)])

    def add_pieces(self, statement: Statement, text: str, line: int, col: int) -> None:
        for piece, piece_col in _split(text, col):
            if self.function is not None:
                self.function.values.append(Value(piece, line, piece_col))
                continue
            if not piece:
                continue
            key, eq, value = piece.partition("=")
            if eq:
                argument = Argument(key.strip().upper(), [], line, piece_col)
                statement.arguments.append(argument)
                value_col = piece_col + len(key) + 1 + len(value) - len(value.lstrip())
                if argument.key.startswith("FUN"):
                    self.function = argument
                    rest = text[value_col - col:]
                    argument.values.append(Value(rest.strip(), line, value_col))
                    return
                argument.values.append(Value(value.strip(), line, value_col))
            elif statement.arguments and statement.arguments[-1].values:
                statement.arguments[-1].values.append(Value(piece, line, piece_col))
            else:
                statement.arguments.append(Argument(piece.upper(), [], line, piece_col))

    def start(self, code: str, number: int, raw: str) -> Statement:
        match = _HEAD.match(code)
        if match is None:
            word = code.strip()
            if word.upper() == "END":
                return Statement("END", "", number, text=[raw])
            col = len(code) - len(code.lstrip()) + 1
            raise self.error(number, col, f"not an Adams statement: '{word}'",
                             "NAME/id, arguments (e.g. 'PART/2, MASS = 1'), a line starting "
                             "with ',' (continuation) or '!' (comment)",
                             "each statement starts with its name and a slash")
        statement = Statement(match.group(1).upper(), match.group(2).strip(), number,
                              comments=self.pending, text=[raw])
        self.pending = []
        self.function = None
        self.add_pieces(statement, code[match.end():], number, match.end() + 1)
        return statement

    def feed(self, number: int, raw: str) -> bool:
        """One line; returns False at END."""
        code, comment = _code_and_comment(raw)
        if not code.strip():
            if comment is not None:
                self.pending.append(comment)
            return True
        if code.lstrip().startswith(","):
            if not self.statements:
                col = len(code) - len(code.lstrip()) + 1
                raise self.error(number, col, "continuation line before any statement",
                                 "a statement such as 'PART/2, MASS = 1' above it",
                                 "a line starting with ',' continues the statement above")
            statement = self.statements[-1]
            statement.text.append(raw)
            offset = code.index(",") + 1
            if self.function is not None:
                self.function.values.append(Value(code[offset:].strip(), number, offset + 1))
            else:
                self.add_pieces(statement, code[offset:], number, offset + 1)
            statement.comments.extend([comment] if comment else [])
            return True
        statement = self.start(code, number, raw)
        if comment:
            statement.comments.append(comment)
        if statement.name == "END":
            return False
        self.statements.append(statement)
        return True


def parse_adm(text: str, file: str) -> Dataset:
    """Split a dataset into statements; raises ModelError (located) for malformed lines."""
    lines = text.splitlines()
    title = lines[0].strip() if lines else ""
    builder = _Builder(file)
    for number, raw in enumerate(lines[1:], start=2):
        if not builder.feed(number, raw):
            break
    return Dataset(file, title, builder.statements, builder.pending)


def function_text(argument: Argument) -> str:
    """The text of a FUNCTION argument, continuation lines joined."""
    return " ".join(v.text for v in argument.values if v.text)
