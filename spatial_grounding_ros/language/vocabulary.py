# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
The word classes of what people say to a robot, beyond a reference's own words.

A reference's words (directions with their steps, extremes, numbers, relation wordings) are
in checks.py and wording.py; this module holds what the reading (reading.py) needs to tell
what an instruction asks for: its intent, a correction, a sequence, a question, a length
unit, and the words that only pass time. Each list is written from how people talk to a
robot; a phrase is lower-case words as `core.text.tokenize` gives them.
"""

from __future__ import annotations

# "stop", "cancel that", "never mind": the whole request, when nothing else is said
STOP_WORDS = frozenset(
    """
    stop halt cancel abort freeze nevermind never mind forget stay hold wait still stand
    that it this everything all goal mission task now right there here put moving move
    don't dont do not emergency please robot the immediately at once on enough that's quit
    pause brake where you are your tracks
    """.split()
)
# ... at least one of these must be there for a stop
STOP_HEADS = frozenset(
    'stop halt cancel abort freeze nevermind mind forget stay hold wait enough quit pause brake '
    "don't dont".split()
)
# how a question opens ("where is the fridge", "is there a printer", "do you see a lamp")
QUESTION_OPENERS = (
    'where', "where's", 'wheres', 'what', "what's", 'which', 'how', 'is there', 'are there',
    'is the', 'are the', 'is it', 'do you see', 'can you see', 'do you know', 'can you tell',
    'could you tell', 'tell me where', 'show me where', 'does the map have', 'do we have',
    'have you seen', 'is a', 'is an', 'any',
)
# polite openers of a request, not of a question: "can you go to the fridge?"
REQUEST_OPENERS = (
    'can you', 'could you', 'would you', 'will you', 'can u', 'could u', 'would you please',
    'can you please', 'could you please', 'please can you', 'please could you',
)
# the verbs that ask the robot to go somewhere ("meet me at the bakery", "wait by the door")
GO_VERBS = frozenset(
    """
    go goes going reach move drive head navigate travel get proceed park stop wait meet come
    find walk roll return bring take visit approach
    """.split()
)
# a negation of the request ("don't go to the fridge", "avoid the sofa"): declined, never
# turned into the goal it names
NEGATIONS = (
    "don't", 'dont', 'do not', 'never', 'avoid', 'stay away', 'keep away', 'keep clear',
    'steer clear', 'anywhere but', 'anywhere except', 'anywhere other than', 'except',
    'other than', 'not to', 'not near', 'not at', 'not the', 'not go', 'not by',
    "shouldn't", 'should not', 'must not', "mustn't", 'no need to go',
)
# "X, no wait, Y": the speaker's last word on the place is the one meant
CORRECTIONS = (
    'no wait', 'wait no', 'no sorry', 'sorry', 'i mean', 'i meant', 'actually', 'rather',
    'make that', 'scratch that', 'correction', 'oops', 'or rather', 'no no', 'no', 'instead',
    'my mistake', 'my bad', 'oh wait', 'hmm no', 'i meant to say', 'let me rephrase',
    'change of plan', 'on second thought', 'i take that back', 'no no no',
)
# what separates the steps of a several-step request ("the fridge, then the sofa")
SEQUENCE_MARKS = (
    'and then', 'then', 'after that', 'afterwards', 'after which', 'followed by',
    'and after that', 'finally', 'and finally', 'and lastly', 'lastly',
)
# requests a goal cell cannot answer: a motion, a person, a place only pointed at
UNSUPPORTED = (
    'follow me', 'follow', 'turn left', 'turn right', 'turn around', 'turn', 'go back',
    'come back', 'come here', 'come to me', 'over here', 'go there', 'over there', 'go home',
    'go forward', 'move forward', 'go straight', 'back up', 'reverse', 'spin', 'rotate',
    'go away', 'explore', 'dance', 'look at me', 'this way', 'that way', 'go left',
    'go right', 'move left', 'move right', 'go up', 'go down', 'move back', 'move up',
    'move down', 'keep going', 'go ahead', 'get closer', 'come closer', 'back off',
    'come with me', 'go home', 'return to base', 'go to sleep', 'power off', 'shut down',
    'look around', 'wait for me', 'move forward', 'go straight ahead', 'bring me', 'pick up',
)
# a motion asked for, whatever it names ("follow the wall", "turn towards the door")
MOTIONS = (
    'follow', 'turn', 'spin', 'rotate', 'dance', 'explore', 'wander', 'patrol', 'pick', 'grab',
    'fetch', 'clean', 'open', 'close', 'push', 'pull', 'lift', 'carry', 'sing', 'play', 'charge',
    'dock', 'look at',
)
# a go verb's particle before "to": "go over to the lamp", "head back to the desk"
PARTICLES = frozenset('over up down out back on'.split())
# words that point at a place or thing said before or shown, never named ("go there")
DEICTIC = frozenset('there here it that this them me us you'.split())
# "across the street", "down the hall": a path or a place passed, not the place to go
PATH_WORDS = frozenset(
    'across along through past around down up into toward towards over via behind'.split()
)
# lengths people give in units of their own, in metres ("6 feet", "a metre and a half")
LENGTH_UNITS = {
    'm': 1.0, 'metre': 1.0, 'meter': 1.0, 'metres': 1.0, 'meters': 1.0,
    'cm': 0.01, 'centimetre': 0.01, 'centimeter': 0.01, 'centimetres': 0.01,
    'centimeters': 0.01, 'mm': 0.001, 'millimetre': 0.001, 'millimeter': 0.001,
    'millimetres': 0.001, 'millimeters': 0.001, 'ft': 0.3048, 'foot': 0.3048,
    'feet': 0.3048, 'yd': 0.9144, 'yard': 0.9144, 'yards': 0.9144, 'inch': 0.0254,
    'inches': 0.0254, 'km': 1000.0,
}  # fmt: skip
# the commonest slips of the words around a place, read as meant before anything else: the
# spelling reads only words that move a goal, and would read "teh" as "ten"
SLIPS = {'teh': 'the', 'hte': 'the', 'th': 'the', 'adn': 'and', 'nad': 'and'}
# words that pass time in a request and never matter ("um okay robot ... thanks")
FILLERS = frozenset(
    """
    please um uh erm hmm ok okay hey hi hello robot buddy thanks kindly just
    alright quickly carefully slowly yeah yes sure mate pal friend dear
    """.split()
)
