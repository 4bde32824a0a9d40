"""The corpus cases that hang on the CSV reader (io/_csv.py): a row longer than the
header, a decimal comma, a repeated column name, a field over 128 KiB, a non-UTF-8 byte
named at its line. They fail until the reader is rewritten (the records engineer's issue);
they are kept apart so that the lead can reconcile them with the new reader."""

import pytest
from corpus_cases import check, params


@pytest.mark.parametrize("name, command, expect, says, warns", params("csv", reader=True))
def test_reader_case_on_the_command_line(tmp_path, name, command, expect, says, warns):
    check(tmp_path, name, command, expect, says, warns)
