#!/usr/bin/env /usr/bin/python3
"""LaneSegNet: the small encoder-decoder lanemap ships for semantic segmentation (METHOD.md section 2).

A U-Net-shaped network sized for a 2-core CPU (training and inference): four stride-2 stages
(1/2 .. 1/16 of the input) of 3x3 conv + BatchNorm + ReLU, dilated convolutions at 1/16 for
context (deciding ego / left / right lane needs the whole road width), and a decoder that
upsamples by 2 (bilinear) and concatenates the encoder's skip features back up to 1/2 of the
input resolution. No convolution runs at full resolution (on a CPU their memory traffic costs more
than all the rest). The head at 1/2 gives, per class, the logits of the 2 x 2 input pixels under
each of its cells, and a pixel shuffle (DepthToSpace) lays them out at the full input resolution
(logits="full", v2): a 15 cm line 20 m ahead is about one camera pixel wide, and at half resolution
no model can place it (the ceiling of a 160 x 88 label grid on the validation frames is 0.70
dashed-line IoU, of a 480 x 176 grid over the frame below its top 120 rows 0.89). logits="half" is v1's
head (logits at 1/2). The segmenter upsamples the logits (bilinear) to the camera frame before the
per-pixel argmax, which keeps thin markings' edges sub-pixel.

Only operations OpenCV's DNN importer (4.6) handles are used: Conv, BatchNormalization (folded
at export), Relu, Resize (scale 2, bilinear, half-pixel), Concat, DepthToSpace.
"""
import torch
import torch.nn as nn
import torch.nn.functional as F

NUM_CLASSES = 11


class ConvBNReLU(nn.Sequential):
    def __init__(self, cin, cout, stride=1, dilation=1, k=3):
        pad = dilation * (k // 2)
        super().__init__(
            nn.Conv2d(cin, cout, k, stride=stride, padding=pad, dilation=dilation, bias=False),
            nn.BatchNorm2d(cout),
            nn.ReLU(inplace=True),
        )


class Up2(nn.Module):
    def forward(self, x):
        return F.interpolate(x, scale_factor=2.0, mode="bilinear", align_corners=False)


# Architectures by name (train.py --arch). "v3": the shipped lanesegnet-v3. "small" (issue 17: 25 ms
# a frame on one core): narrower first encoder stages, a decoder half as wide and a 1x1 head, where
# v3 spends most of its time (lanemap-bench-seg's per-module profile: the half-resolution decoder
# stage and the 3x3 head are 46 % of v3's forward pass). Untrained, through the segmenter on one
# thread in one run (2026-12-06): small 23.0 ms a frame, v3 43.3.
ARCHS = {
    "v3": dict(width=(16, 32, 64, 96), decoder=(64, 32, 24), head_kernel=3),
    "small": dict(width=(12, 24, 48, 96), decoder=(32, 16, 12), head_kernel=1),
}


class LaneSegNet(nn.Module):
    def __init__(self, num_classes=NUM_CLASSES, width=(16, 32, 64, 96), logits="full", decoder=(64, 32, 24), head_kernel=3):
        super().__init__()
        if logits not in ("full", "half"):
            raise ValueError("logits must be 'full' or 'half'")
        self.logits = logits
        c1, c2, c3, c4 = width
        d3, d2, d1 = decoder
        self.enc1 = ConvBNReLU(3, c1, 2)                                        # 1/2
        self.enc2 = nn.Sequential(ConvBNReLU(c1, c2, 2), ConvBNReLU(c2, c2))   # 1/4
        self.enc3 = nn.Sequential(ConvBNReLU(c2, c3, 2), ConvBNReLU(c3, c3))   # 1/8
        self.enc4 = nn.Sequential(ConvBNReLU(c3, c4, 2), ConvBNReLU(c4, c4, dilation=2),
                                  ConvBNReLU(c4, c4, dilation=4))              # 1/16
        self.up = Up2()
        self.dec3 = ConvBNReLU(c4 + c3, d3)                                    # 1/8
        self.dec2 = ConvBNReLU(d3 + c2, d2)                                    # 1/4
        self.dec1 = ConvBNReLU(d2 + c1, d1)                                    # 1/2
        shuffle = 4 if logits == "full" else 1                                  # 2 x 2 pixels per cell
        self.head = nn.Conv2d(d1, num_classes * shuffle, head_kernel, padding=head_kernel // 2)  # logits at 1/2

    def forward(self, x):
        e1 = self.enc1(x)
        e2 = self.enc2(e1)
        e3 = self.enc3(e2)
        e4 = self.enc4(e3)
        d3 = self.dec3(torch.cat([self.up(e4), e3], 1))
        d2 = self.dec2(torch.cat([self.up(d3), e2], 1))
        d1 = self.dec1(torch.cat([self.up(d2), e1], 1))
        out = self.head(d1)
        return F.pixel_shuffle(out, 2) if self.logits == "full" else out


if __name__ == "__main__":
    import sys
    import time
    torch.set_num_threads(int(sys.argv[1]) if len(sys.argv) > 1 else 2)
    h, w = (int(sys.argv[2]), int(sys.argv[3])) if len(sys.argv) > 3 else (176, 480)
    net = LaneSegNet(**ARCHS[sys.argv[4] if len(sys.argv) > 4 else "v3"])
    print("params", sum(p.numel() for p in net.parameters()))
    x = torch.randn(8, 3, h, w)
    y = torch.randint(0, NUM_CLASSES, (8, h, w))
    opt = torch.optim.AdamW(net.parameters(), 1e-3)
    for i in range(4):
        t = time.time()
        loss = F.cross_entropy(net(x), y)
        opt.zero_grad()
        loss.backward()
        opt.step()
        print("train batch 8: %.2f s" % (time.time() - t))
