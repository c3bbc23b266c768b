"""Fresh weights as crate/model/init.rs and the Rust constructors draw them (not the same
numbers: the same distributions).

He-uniform weights (U(±√(6 / fan_in))) and zero biases for every layer of the encoders and
decoders: PyTorch's default (a third of that variance, biases as large as the weights) through
the joint encoder's seven ReLU layers leaves a fresh encoder that barely sees its input. The
exceptions keep burn's (= PyTorch's) default: DMBN-PTE's time projection P(t) and the
attention's four projections. LayerNorm starts at 1 and 0, the `observed` embedding at 0; the
attentive model's image gate starts at σ(0) = 1/2 (zero weights and bias), its joint mean head
at a tenth of He's scale (the correction of the interpolated joints starts small), and its
joint read-out from frames at zero (it reads the mean joints until trained).
"""
import torch
import torch.nn as nn

# The joint mean head's starting scale against He's (dmbn_attn.rs JOINT_CORRECTION_SCALE).
JOINT_CORRECTION_SCALE = 0.1
# The gate head's starting bias (image_decoder.rs GATE_BIAS).
GATE_BIAS = 0.0


def he_uniform(layer):
    nn.init.kaiming_uniform_(layer.weight, nonlinearity="relu")  # gain √2, fan in
    nn.init.zeros_(layer.bias)


@torch.no_grad()
def initialise(network, initialization="he"):
    """Draws every weight of a Dmbn, DmbnPte or DmbnAttn (seed torch first for a repeatable
    draw); returns it. `initialization="glorot"` (DMBN and DMBN-PTE): the original Keras
    model's Glorot-uniform weights and zero biases for every dense and convolution layer, as
    `train --initialization glorot`."""
    from .model import MultiHeadAttention, TimeProjection

    if initialization == "glorot":
        if hasattr(network, "observed"):
            raise ValueError("--initialization glorot is for dmbn and pte: the attentive "
                             "model's gates and read-out start from zero by design")
        for module in network.modules():
            if isinstance(module, (nn.Linear, nn.Conv2d)):
                nn.init.xavier_uniform_(module.weight)  # fans count receptive fields
                nn.init.zeros_(module.bias)
        return network

    keep_default = set()
    for module in network.modules():
        if isinstance(module, (TimeProjection, MultiHeadAttention)):
            keep_default.update(module.modules())
    for module in network.modules():
        if isinstance(module, (nn.Linear, nn.Conv2d)):
            if module in keep_default:
                module.reset_parameters()
            else:
                he_uniform(module)
        elif isinstance(module, nn.LayerNorm):
            nn.init.ones_(module.weight)
            nn.init.zeros_(module.bias)
    if hasattr(network, "observed"):  # the attentive model
        network.observed.zero_()
        gate = network.decoder.image.gate
        gate.weight.zero_()
        gate.bias.fill_(GATE_BIAS)
        network.decoder.joint.mean.weight.mul_(JOINT_CORRECTION_SCALE)
        if network.frame_joints is not None:
            read_nothing(network.frame_joints)
    return network


@torch.no_grad()
def read_nothing(layer):
    """A joint read-out from frames that reads the mean joints (0 normalised): a model given
    one predicts as before, and training teaches it."""
    layer.weight.zero_()
    layer.bias.zero_()
