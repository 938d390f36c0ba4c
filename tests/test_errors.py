"""How error sentences name a setting: the flag on the command line, the keyword in Python."""

from translucency.errors import command_line_spelling, option


def test_option_is_the_keyword_in_python():
    assert option("unit") == "unit="
    assert option("unit", "m") == "unit='m'"
    assert option("memory_limit", 4) == "memory_limit=4"


def test_option_is_the_flag_on_the_command_line_and_restored_after():
    with command_line_spelling():
        assert option("unit", "m") == "--unit m"
        assert option("light_dir") == "--light-dir"
    assert option("light_dir") == "light_dir="
